// Datasets, frames and trajectory files.

#include "common.hpp"

#include "rgbl/io/sequence.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include <array>
#include <optional>
#include <string>

namespace rgbl::python {
namespace {

LoadOptions load_options(const std::optional<std::array<bool, 4>>& cameras, bool lidar, bool depth) {
  LoadOptions o;
  if (cameras) o.cameras = *cameras;
  o.lidar = lidar;
  o.depth = depth;
  return o;
}

}  // namespace

void bind_io(py::module_& m) {
  py::class_<Trajectory>(m, "Trajectory",
                         "Poses (float64 N x 4 x 4, T_world_cam) with their timestamps (float64 N, seconds; may "
                         "be empty for KITTI files). The arrays share the object's memory.")
      .def(py::init([](const PosesArg& poses, const py::object& timestamps) {
             Trajectory t;
             const PosesView view = poses_view(poses, "poses");
             t.poses.assign(view.poses.begin(), view.poses.end());
             if (!timestamps.is_none()) t.timestamps = timestamps.cast<std::vector<double>>();
             if (!t.timestamps.empty() && t.timestamps.size() != t.poses.size()) {
               throw py::value_error("timestamps: one per pose, or none");
             }
             return t;
           }),
           py::arg("poses"), py::arg("timestamps") = py::none())
      .def_property_readonly("poses", [](const py::object& self) {
        return poses_array(self.cast<const Trajectory&>().poses, self);
      })
      .def_property_readonly("timestamps", [](const py::object& self) {
        const auto& t = self.cast<const Trajectory&>().timestamps;
        return py::array_t<double>(static_cast<py::ssize_t>(t.size()), t.data(), self);
      })
      .def("__len__", &Trajectory::size);

  m.def("read_kitti_trajectory", [](const std::filesystem::path& file) { return poses_array(read_kitti_trajectory(file)); },
        py::arg("file"), "A KITTI trajectory file (12 numbers per line) as float64 N x 4 x 4.");
  m.def(
      "write_kitti_trajectory",
      [](const std::filesystem::path& file, const PosesArg& poses) {
        write_kitti_trajectory(file, poses_view(poses, "poses").poses);
      },
      py::arg("file"), py::arg("poses"),
      "Writes N x 4 x 4 poses as a KITTI trajectory (shortest round-trip numbers; written whole, then renamed).");
  m.def("read_tum_trajectory", [](const std::filesystem::path& file) { return read_tum_trajectory(file); }, py::arg("file"), "A TUM trajectory (t tx ty tz qx qy qz qw).");
  m.def("write_tum_trajectory", &write_tum_trajectory, py::arg("file"), py::arg("trajectory"));
  m.def("read_kitti_scan", [](const std::filesystem::path& file) { return scan_array(read_kitti_scan(file)); },
        py::arg("file"), "A KITTI velodyne .bin as float32 N x 4 (x, y, z, reflectance).");

  py::enum_<DatasetFormat>(m, "DatasetFormat")
      .value("automatic", DatasetFormat::automatic)
      .value("kitti", DatasetFormat::kitti)
      .value("kitti_raw", DatasetFormat::kitti_raw)
      .value("tum", DatasetFormat::tum);

  py::class_<SensorSet>(m, "SensorSet", "Which sensors a dataset provides.")
      .def_readonly("cameras", &SensorSet::cameras, "Cameras 0..3 present.")
      .def_readonly("lidar", &SensorSet::lidar)
      .def_readonly("depth", &SensorSet::depth)
      .def("__repr__", [](const SensorSet& s) {
        return py::str("SensorSet(cameras={}, lidar={}, depth={})").format(s.cameras, s.lidar, s.depth);
      });

  py::class_<FrameInput>(m, "Frame",
                         "One loaded frame. Arrays share the frame's memory (no copies): images[i] uint8 "
                         "H x W (grey, cameras 0/1) or H x W x 3 (BGR, 2/3), None when absent; scan float32 "
                         "N x 4; depth float32 H x W or None; T_world_cam0 float64 4 x 4 or None.")
      .def_readonly("index", &FrameInput::index)
      .def_readonly("timestamp", &FrameInput::timestamp)
      .def_readonly("scan_timestamp", &FrameInput::scan_timestamp,
                    "When the scan faced forward (KITTI raw), on the timestamp's clock; None when not given.")
      .def_property_readonly("images", [](const py::object& self) {
        py::list out;
        for (const cv::Mat& image : self.cast<const FrameInput&>().images) out.append(mat_array(image, self));
        return out;
      })
      .def_property_readonly("scan", [](const py::object& self) {
        return scan_array(self.cast<const FrameInput&>().scan, self);
      })
      .def_property_readonly("depth", [](const py::object& self) {
        return mat_array(self.cast<const FrameInput&>().depth, self);
      })
      .def_property_readonly("T_world_cam0", [](const FrameInput& f) -> py::object {
        if (!f.T_world_cam0) return py::none();
        return pose_array(*f.T_world_cam0);
      });

  py::class_<Sequence>(m, "Sequence",
                       "A dataset as a sequence of frames (KITTI odometry, KITTI raw, TUM RGB-D), checked "
                       "whole when opened.")
      .def_property_readonly("format", &Sequence::format)
      .def_property_readonly("name", &Sequence::name)
      .def_property_readonly("path", &Sequence::path)
      .def_property_readonly("sensors", &Sequence::sensors)
      .def_property_readonly("calibration", &Sequence::calibration, py::return_value_policy::reference_internal)
      .def_property_readonly("notes", &Sequence::notes)
      .def("__len__", &Sequence::size)
      .def("timestamp", &Sequence::timestamp, py::arg("index"))
      .def_property_readonly("ground_truth", [](const py::object& self) -> py::object {
        const auto& gt = self.cast<const Sequence&>().ground_truth();
        if (!gt) return py::none();
        return py::cast(&*gt, py::return_value_policy::reference_internal, self);
      }, "T_world_cam0 of the frames as a Trajectory (KITTI: one per frame), or None.")
      .def(
          "load",
          [](const Sequence& s, std::size_t index, const std::optional<std::array<bool, 4>>& cameras, bool lidar,
             bool depth) {
            if (index >= s.size()) throw py::index_error("frame " + std::to_string(index) + " of " + std::to_string(s.size()));
            const LoadOptions options = load_options(cameras, lidar, depth);
            const py::gil_scoped_release release;
            return s.load(index, options);
          },
          py::arg("index"), py::arg("cameras") = py::none(), py::arg("lidar") = true, py::arg("depth") = true,
          "Reads frame `index` (cameras: four booleans, None = those the sequence was opened with). Raises "
          "ParseError naming a missing or corrupt file.");

  m.def(
      "check_sequence",
      [](const Sequence& sequence) {
        std::vector<LoadProblem> problems;
        {
          const py::gil_scoped_release release;
          problems = check_sequence(sequence);
        }
        py::list out;
        for (const LoadProblem& p : problems) out.append(py::make_tuple(p.frame, p.message));
        return out;
      },
      py::arg("sequence"),
      "Loads every file of every frame, one sensor at a time: a (frame, message) per file that does not load "
      "(the message names the file); empty when all load. What `rgbl info --check` lists.");

  m.def(
      "open_sequence",
      [](const std::filesystem::path& path, const std::string& format,
         const std::optional<std::array<bool, 4>>& cameras, bool lidar, bool depth) {
        const DatasetFormat f = parse_dataset_format(format);
        const LoadOptions options = load_options(cameras, lidar, depth);
        const py::gil_scoped_release release;
        return open_sequence(path, f, options);
      },
      py::arg("path"), py::arg("format") = "auto", py::arg("cameras") = py::none(), py::arg("lidar") = true,
      py::arg("depth") = true,
      "Opens a dataset folder: KITTI odometry sequences/NN, a KITTI raw drive or a TUM RGB-D folder (format "
      "'auto', 'kitti', 'kitti-raw' or 'tum'). Checks every frame's files once; raises ParseError or "
      "ConfigError naming what is wrong.");
}

}  // namespace rgbl::python
