// Trajectory metrics: ATE, RPE, end-point drift, the KITTI metric. Poses are float64 N x 4 x 4.

#include "common.hpp"

#include "rgbl/eval/trajectory_metrics.hpp"

#include <optional>
#include <string>

namespace rgbl::python {
namespace {

// The estimate and ground truth of one call, viewed (or copied) once.
struct PosePair {
  PosesView estimate, ground_truth;
  PosePair(const py::handle& e, const py::handle& g)
      : estimate(poses_view(e, "estimate")), ground_truth(poses_view(g, "ground_truth")) {
    if (estimate.poses.size() != ground_truth.poses.size()) {
      throw py::value_error("estimate and ground_truth: " + std::to_string(estimate.poses.size()) + " and " +
                            std::to_string(ground_truth.poses.size()) + " poses; they must be equally many");
    }
  }
};

}  // namespace

void bind_eval(py::module_& m) {
  py::class_<ErrorStats>(m, "ErrorStats", "Statistics of per-pose errors (NaN for no samples).")
      .def_readonly("rmse", &ErrorStats::rmse)
      .def_readonly("mean", &ErrorStats::mean)
      .def_readonly("median", &ErrorStats::median)
      .def_readonly("max", &ErrorStats::max)
      .def("__repr__", [](const ErrorStats& s) {
        return py::str("ErrorStats(rmse={}, mean={}, median={}, max={})").format(s.rmse, s.mean, s.median, s.max);
      });

  py::class_<AteResult>(m, "AteResult", "Absolute trajectory error after the rigid (SE3) Umeyama alignment.")
      .def_readonly("translation", &AteResult::translation, "ErrorStats, metres.")
      .def_property_readonly("T_gt_est", [](const AteResult& r) { return pose_array(r.T_gt_est); },
                             "The alignment applied to the estimate.")
      .def_property_readonly("errors", [](const py::object& self) {
        const auto& e = self.cast<const AteResult&>().errors;
        return py::array_t<double>(static_cast<py::ssize_t>(e.size()), e.data(), self);
      }, "Per pose, metres.");

  py::class_<RpeResult>(m, "RpeResult", "Relative pose error over pairs (i, i + delta).")
      .def_readonly("translation", &RpeResult::translation, "ErrorStats, metres per delta frames.")
      .def_readonly("rotation_deg", &RpeResult::rotation_deg, "ErrorStats, degrees per delta frames.")
      .def_property_readonly("translation_errors", [](const py::object& self) {
        const auto& e = self.cast<const RpeResult&>().translation_errors;
        return py::array_t<double>(static_cast<py::ssize_t>(e.size()), e.data(), self);
      })
      .def_property_readonly("rotation_errors_deg", [](const py::object& self) {
        const auto& e = self.cast<const RpeResult&>().rotation_errors_deg;
        return py::array_t<double>(static_cast<py::ssize_t>(e.size()), e.data(), self);
      });

  py::class_<DriftResult>(m, "DriftResult", "End-point drift: the error between the first and last frame.")
      .def_readonly("path_length", &DriftResult::path_length, "m, ground truth")
      .def_readonly("end_error", &DriftResult::end_error, "m")
      .def_readonly("percent", &DriftResult::percent, "end_error / path_length x 100");

  py::class_<KittiMetricOptions>(m, "KittiMetricOptions", "Segment lengths (m) and start-frame step of the KITTI metric.")
      .def(py::init<>())
      .def_readwrite("lengths", &KittiMetricOptions::lengths)
      .def_readwrite("step_size", &KittiMetricOptions::step_size);
  py::class_<KittiLengthError>(m, "KittiLengthError")
      .def_readonly("length", &KittiLengthError::length)
      .def_readonly("segments", &KittiLengthError::segments)
      .def_readonly("t_err_percent", &KittiLengthError::t_err_percent)
      .def_readonly("r_err_deg_per_100m", &KittiLengthError::r_err_deg_per_100m);
  py::class_<KittiMetric>(m, "KittiMetric", "The KITTI odometry devkit's metric (means over all segments).")
      .def_readonly("segments", &KittiMetric::segments, "0 when the run is shorter than the shortest length.")
      .def_readonly("t_err_percent", &KittiMetric::t_err_percent, "%, NaN without segments.")
      .def_readonly("r_err_deg_per_100m", &KittiMetric::r_err_deg_per_100m, "deg/100 m, NaN without segments.")
      .def_readonly("per_length", &KittiMetric::per_length);

  py::class_<TrajectoryEvaluation>(m, "TrajectoryEvaluation", "Every metric at once, as `rgbl run` reports them.")
      .def_readonly("poses", &TrajectoryEvaluation::poses)
      .def_readonly("path_length", &TrajectoryEvaluation::path_length, "m, ground truth")
      .def_readonly("estimated_path_length", &TrajectoryEvaluation::estimated_path_length, "m, the estimate's own")
      .def_readonly("kitti_options", &TrajectoryEvaluation::kitti_options)
      .def_readonly("kitti", &TrajectoryEvaluation::kitti)
      .def_readonly("ate", &TrajectoryEvaluation::ate)
      .def_readonly("rpe", &TrajectoryEvaluation::rpe)
      .def_readonly("drift", &TrajectoryEvaluation::drift);

  m.def(
      "absolute_trajectory_error",
      [](const PosesArg& estimate, const PosesArg& ground_truth, bool align) {
        const PosePair p(estimate, ground_truth);
        return absolute_trajectory_error(p.estimate.poses, p.ground_truth.poses, align);
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("align") = true,
      "ATE: RMSE of positions after aligning the estimate to the ground truth (align=False: as given).");
  m.def(
      "relative_pose_error",
      [](const PosesArg& estimate, const PosesArg& ground_truth, std::size_t delta) {
        const PosePair p(estimate, ground_truth);
        return relative_pose_error(p.estimate.poses, p.ground_truth.poses, delta);
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("delta") = 1);
  m.def(
      "end_point_drift",
      [](const PosesArg& estimate, const PosesArg& ground_truth) {
        const PosePair p(estimate, ground_truth);
        return end_point_drift(p.estimate.poses, p.ground_truth.poses);
      },
      py::arg("estimate"), py::arg("ground_truth"));
  m.def(
      "kitti_metric",
      [](const PosesArg& estimate, const PosesArg& ground_truth, const std::optional<std::vector<double>>& lengths,
         std::size_t step_size) {
        const PosePair p(estimate, ground_truth);
        KittiMetricOptions o;
        if (lengths) o.lengths = *lengths;
        o.step_size = step_size;
        o.validate();
        return kitti_metric(p.estimate.poses, p.ground_truth.poses, o);
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("lengths") = py::none(), py::arg("step_size") = 10,
      "The KITTI devkit metric over segments of `lengths` metres (None: KITTI's 100..800 m).");
  m.def(
      "evaluate_trajectory",
      [](const PosesArg& estimate, const PosesArg& ground_truth) {
        const PosePair p(estimate, ground_truth);
        return evaluate_trajectory(p.estimate.poses, p.ground_truth.poses);
      },
      py::arg("estimate"), py::arg("ground_truth"),
      "ATE, RPE, drift and the KITTI metric (with lengths that suit the path) at once; needs >= 2 poses.");
  m.def(
      "trajectory_distances",
      [](const PosesArg& poses) { return doubles_array(trajectory_distances(poses_view(poses, "poses").poses)); },
      py::arg("poses"), "Cumulative path length of the positions, starting at 0.");
}

}  // namespace rgbl::python
