// The tracking facade: System.track, one call per frame from numpy arrays to a pose.

#include "common.hpp"

#include "rgbl/depth/sources.hpp"
#include "rgbl/io/trajectory_io.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/system.hpp"

#include <memory>
#include <optional>
#include <shared_mutex>
#include <string>

namespace rgbl::python {
namespace {

// System::trajectory() as arrays.
struct SystemTrajectory {
  std::vector<std::size_t> frame_indices;
  std::vector<TrackState> states;
  Trajectory trajectory;
};

TrackResult track(System& system, const ImageArg& image, const OptionalScanArg& scan, std::optional<std::size_t> index,
                  std::optional<double> timestamp, const OptionalImageArg& image_right, const OptionalImageArg& depth_image,
                  std::optional<double> scan_timestamp, std::size_t tracked, double frame_period) {
  const MatView left = mat_view(image, "image");
  const MatView right = optional_mat_view(image_right, "image_right");
  const MatView depth = optional_mat_view(depth_image, "depth_image");
  const ScanView points = scan_view(scan, "scan");
  SensorFrame frame;
  frame.index = index.value_or(tracked);
  frame.timestamp = timestamp.value_or(static_cast<double>(frame.index) * frame_period);
  frame.image = left.mat;
  frame.image_right = right.mat;
  frame.depth_image = depth.mat;
  frame.scan = points.points;
  frame.scan_timestamp = scan_timestamp;
  // the views' arrays stay referenced by this frame's Python arguments while the GIL is released
  const py::gil_scoped_release release;
  return system.track(frame);
}

// A System with what track() fills in on its own: the frames tracked so far and the frame period.
struct PySystem {
  std::unique_ptr<System> system;
  double frame_period = 0.1;
  std::size_t tracked = 0;
};

}  // namespace

// Wraps a System made elsewhere (Pipeline.make_system) for Python.
py::object wrap_system(std::unique_ptr<System> system, double frame_period) {
  auto s = std::make_unique<PySystem>();
  s->system = std::move(system);
  s->frame_period = frame_period;
  return py::cast(std::move(s));
}

System& unwrap_system(const py::handle& object) { return *object.cast<PySystem&>().system; }

void bind_tracking(py::module_& m) {
  py::enum_<TrackState>(m, "TrackState", "How a frame was tracked.")
      .value("NotInitialised", TrackState::NotInitialised)
      .value("Ok", TrackState::Ok)
      .value("Weak", TrackState::Weak)
      .value("Lost", TrackState::Lost);

  py::class_<StageTiming>(m, "StageTiming", "Milliseconds per stage of one frame.")
      .def_readonly("depth_ms", &StageTiming::depth_ms)
      .def_readonly("extraction_ms", &StageTiming::extraction_ms)
      .def_readonly("tracking_ms", &StageTiming::tracking_ms)
      .def_readonly("mapping_ms", &StageTiming::mapping_ms, "Inline local mapping (0 when threaded).")
      .def_readonly("loop_ms", &StageTiming::loop_ms)
      .def_readonly("front_ms", &StageTiming::front_ms, "Wall, from the frame's turn to its pose.")
      .def_readonly("total_ms", &StageTiming::total_ms, "Wall, the frame's whole turn (building it included).");

  py::class_<LoopClosure>(m, "LoopClosure", "A loop closed: the map was corrected.")
      .def_readonly("frame_index", &LoopClosure::frame_index, "Of the keyframe that closed it.")
      .def_readonly("matched_frame_index", &LoopClosure::matched_frame_index, "Of the older keyframe it matched.")
      .def_readonly("merged", &LoopClosure::merged)
      .def_readonly("bridged", &LoopClosure::bridged, "The merge registered the LiDAR scans across a gap.")
      .def_readonly("place_source", &LoopClosure::place_source)
      .def_readonly("place_similarity", &LoopClosure::place_similarity)
      .def_readonly("inliers", &LoopClosure::inliers)
      .def_readonly("correction_m", &LoopClosure::correction_m)
      .def_readonly("correction_deg", &LoopClosure::correction_deg);

  py::class_<TrackResult>(m, "TrackResult", "The outcome of System.track for one frame.")
      .def_readonly("frame_index", &TrackResult::frame_index)
      .def_readonly("timestamp", &TrackResult::timestamp)
      .def_readonly("state", &TrackResult::state)
      .def_property_readonly("T_world_cam", [](const TrackResult& r) { return pose_array(r.T_world_cam); },
                             "float64 4 x 4; the world is the first tracked camera's frame.")
      .def_readonly("keyframe", &TrackResult::keyframe)
      .def_readonly("relocalised", &TrackResult::relocalised)
      .def_readonly("new_map", &TrackResult::new_map)
      .def_readonly("jump", &TrackResult::jump)
      .def_readonly("step_rejected", &TrackResult::step_rejected)
      .def_readonly("step_registered", &TrackResult::step_registered)
      .def_readonly("step_contested", &TrackResult::step_contested)
      .def_readonly("speed_corrected", &TrackResult::speed_corrected)
      .def_readonly("start_refuted_since", &TrackResult::start_refuted_since)
      .def_readonly("start_by_rays", &TrackResult::start_by_rays)
      .def_readonly("scan_confirmed", &TrackResult::scan_confirmed)
      .def_readonly("gap", &TrackResult::gap)
      .def_readonly("gap_registered", &TrackResult::gap_registered)
      .def_readonly("lost_registered", &TrackResult::lost_registered)
      .def_readonly("inliers", &TrackResult::inliers, "Local-map inliers (Ok needs 30).")
      .def_readonly("keypoints", &TrackResult::keypoints)
      .def_readonly("keypoints_with_depth", &TrackResult::keypoints_with_depth)
      .def_readonly("scan_age", &TrackResult::scan_age, "Seconds the LiDAR depth was moved by (image time - scan time).")
      .def_readonly("map_keyframes", &TrackResult::map_keyframes, "The map's keyframes after this frame.")
      .def_readonly("map_landmarks", &TrackResult::map_landmarks, "The map's landmarks after this frame.")
      .def_readonly("loop_closure", &TrackResult::loop_closure, "A LoopClosure or None.")
      .def_readonly("timing", &TrackResult::timing)
      .def("__repr__", [](const TrackResult& r) {
        return py::str("TrackResult(frame_index={}, state={}, inliers={}, keyframe={})")
            .format(r.frame_index, to_string(r.state), r.inliers, r.keyframe);
      });

  py::class_<SystemTrajectory>(m, "SystemTrajectory",
                               "Every frame tracked so far, with poses refined by mapping (T_world_cam, the world "
                               "being the first tracked camera's frame).")
      .def_readonly("frame_indices", &SystemTrajectory::frame_indices)
      .def_readonly("states", &SystemTrajectory::states)
      .def_property_readonly("timestamps", [](const py::object& self) {
        const auto& t = self.cast<const SystemTrajectory&>().trajectory.timestamps;
        return py::array_t<double>(static_cast<py::ssize_t>(t.size()), t.data(), self);
      })
      .def_property_readonly("poses", [](const py::object& self) {
        return poses_array(self.cast<const SystemTrajectory&>().trajectory.poses, self);
      })
      .def("__len__", [](const SystemTrajectory& t) { return t.states.size(); });

  py::class_<PySystem>(m, "System",
                       "Visual SLAM with metric depth: one call per frame from an image (and a LiDAR scan, a "
                       "right image or a depth image, as the depth source needs) to a pose. Owns the map, the "
                       "tracker, local mapping, loop closing, the depth source and the ORB extractor.\n\n"
                       "Pipeline.make_system() gives the System `rgbl run` tracks with (settings file, dataset "
                       "calibration); the constructor builds one from a calibration with default options.")
      .def(py::init([](const CameraCalibration& calibration, const std::string& depth, const std::optional<OrbOptions>& orb,
                       bool threaded, bool loop_closing, double stereo_baseline) {
             SystemOptions options;
             options.threaded_mapping = threaded;
             options.loop_closing.enabled = loop_closing;
             options.validate();
             DepthSourceContext context;
             context.calibration = calibration;
             context.stereo_baseline = stereo_baseline;
             auto s = std::make_unique<PySystem>();
             s->frame_period = options.frame_period;
             s->system = std::make_unique<System>(options, calibration, builtin_depth_sources().create(depth, context),
                                                  make_orb_extractor(orb.value_or(OrbOptions{})));
             return s;
           }),
           py::arg("calibration"), py::arg("depth") = "lidar", py::arg("orb") = py::none(), py::arg("threaded") = false,
           py::arg("loop_closing") = true, py::arg("stereo_baseline") = 0.0,
           "calibration: the tracked camera (CameraCalibration); depth: a registered depth source spec "
           "(depth_source_names()); threaded: local mapping and loop closing in threads of their own (inline, the "
           "default, is bit-for-bit reproducible).")
      .def(
          "track",
          [](PySystem& s, const ImageArg& image, const OptionalScanArg& scan, std::optional<std::size_t> index,
             std::optional<double> timestamp, const OptionalImageArg& image_right, const OptionalImageArg& depth_image,
             std::optional<double> scan_timestamp) {
            TrackResult r = track(*s.system, image, scan, index, timestamp, image_right, depth_image, scan_timestamp,
                                  s.tracked, s.frame_period);
            ++s.tracked;
            return r;
          },
          py::arg("image"), py::arg("scan") = py::none(), py::kw_only(), py::arg("index") = py::none(),
          py::arg("timestamp") = py::none(), py::arg("image_right") = py::none(), py::arg("depth_image") = py::none(),
          py::arg("scan_timestamp") = py::none(),
          "Tracks one frame and returns its TrackResult. image: uint8 H x W grey or H x W x 3 BGR (the tracked "
          "rectified camera); scan: float32 N x 4 LiDAR points (x, y, z, reflectance) in the LiDAR frame; "
          "image_right: the stereo pair's right image; depth_image: float32 metres or uint16. Arrays are read in "
          "place (no copies) and the GIL is released while C++ tracks. index defaults to the frames tracked so "
          "far, timestamp to index x the frame period (0.1 s); scan_timestamp: when the scan faced forward, on the "
          "timestamp's clock (the LiDAR depth is then moved to the image's time). Raises ConfigError when the depth source lacks "
          "its input (e.g. no right image for stereo).")
      .def("finish", [](PySystem& s) {
        const py::gil_scoped_release release;
        s.system->finish();
      }, "Waits for threaded mapping and loop closing to process every queued keyframe (no-op inline).")
      .def("trajectory", [](const PySystem& s) {
        SystemTrajectory out;
        for (const auto& p : s.system->trajectory()) {
          out.frame_indices.push_back(p.frame_index);
          out.states.push_back(p.state);
          out.trajectory.timestamps.push_back(p.timestamp);
          out.trajectory.poses.push_back(p.T_world_cam);
        }
        return out;
      }, "Every frame so far as a SystemTrajectory.")
      .def_property_readonly("calibration", [](const PySystem& s) { return s.system->calibration(); })
      .def_property_readonly("loop_closing", [](const PySystem& s) { return s.system->loop_closing(); })
      .def("loop_closures", [](const PySystem& s) { return s.system->loop_closures(); }, "Every closure so far.")
      .def_property_readonly("keyframe_count", [](const PySystem& s) {
        const std::shared_lock lock(s.system->map().mutex());
        return s.system->map().keyframe_count();
      }, "Keyframes in the map now.")
      .def_property_readonly("landmark_count", [](const PySystem& s) {
        const std::shared_lock lock(s.system->map().mutex());
        return s.system->map().landmark_count();
      }, "Landmarks in the map now.")
      .def_readonly("frames_tracked", &PySystem::tracked, "Calls of track() so far.");
}

}  // namespace rgbl::python
