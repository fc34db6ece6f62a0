#include "rgbl/pipeline/describe.hpp"

#include "rgbl/eval/trajectory_metrics.hpp"

#include <fmt/format.h>

#include <array>
#include <iterator>

namespace rgbl {

std::string describe_sequence(const Sequence& seq) {
  std::string s;
  const auto out = std::back_inserter(s);
  fmt::format_to(out, "dataset:       {} ({})\n", seq.path().string(), to_string(seq.format()));
  fmt::format_to(out, "name:          {}\n", seq.name());
  const double span = seq.timestamp(seq.size() - 1) - seq.timestamp(0);
  fmt::format_to(out, "frames:        {} over {:.3f} s", seq.size(), span);
  if (seq.size() > 1 && span > 0.0) fmt::format_to(out, " ({:.2f} Hz)", static_cast<double>(seq.size() - 1) / span);
  fmt::format_to(out, "\n");

  const auto& calib = seq.calibration();
  const SensorSet& sensors = seq.sensors();
  static constexpr std::array<const char*, 4> kCameraNames = {"grey left", "grey right", "colour left", "colour right"};
  for (std::size_t c = 0; c < kCameraNames.size(); ++c) {
    if (!sensors.cameras[c]) continue;
    const CameraCalibration cam = calib.camera(static_cast<int>(c));
    const Eigen::Vector3d t = cam.T_cam_cam0.translation();
    fmt::format_to(out,
                   "camera {}:      {:<12} {}x{}  fx {:.4f} fy {:.4f} cx {:.4f} cy {:.4f}  T_cam_cam0 t = ({:.4f}, "
                   "{:.4f}, {:.4f}) m\n",
                   c, kCameraNames[c], cam.camera.width, cam.camera.height, cam.camera.fx,
                   cam.camera.fy, cam.camera.cx, cam.camera.cy, t.x(), t.y(), t.z());
  }
  if (sensors.lidar) {
    const Eigen::Vector3d t = calib.T_cam0_lidar.translation();
    const Eigen::Vector3d cam0_in_lidar = calib.T_cam0_lidar.inverse().translation();
    LoadOptions lidar_only;
    lidar_only.cameras = {false, false, false, false};
    lidar_only.depth = false;
    const FrameInput first = seq.load(0, lidar_only);
    fmt::format_to(out,
                   "lidar:         {} points in frame 0; T_cam0_lidar t = ({:.4f}, {:.4f}, {:.4f}) m; cam0 sits at "
                   "({:.3f}, {:.3f}, {:.3f}) m in the LiDAR frame\n",
                   first.scan.size(), t.x(), t.y(), t.z(), cam0_in_lidar.x(), cam0_in_lidar.y(), cam0_in_lidar.z());
    if (first.scan_timestamp) {
      // the LiDAR depth is moved by the camera's motion over this time (docs/depth.md)
      fmt::format_to(out, "scan times:    frame 0's image {:.1f} ms after its scan faced forward\n",
                     (first.timestamp - *first.scan_timestamp) * 1000.0);
    }
  } else {
    fmt::format_to(out, "lidar:         none\n");
  }
  fmt::format_to(out, "depth camera:  {}\n", sensors.depth ? "yes (metres)" : "none");
  if (const auto& gt = seq.ground_truth()) {
    const double length = gt->empty() ? 0.0 : trajectory_distances(gt->poses).back();
    fmt::format_to(out, "ground truth:  {} poses (T_world_cam0), path {:.2f} m\n", gt->size(), length);
  } else {
    fmt::format_to(out, "ground truth:  none\n");
  }
  for (const auto& note : seq.notes()) fmt::format_to(out, "note:          {}\n", note);
  return s;
}

}  // namespace rgbl
