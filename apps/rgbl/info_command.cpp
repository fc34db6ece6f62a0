// rgbl info <dir>: what the loader sees in a dataset folder.
#include "command.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/io/sequence.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rgbl::cli {
namespace {

struct InfoArgs {
  std::filesystem::path dir;
  std::string format = "auto";
  bool check = false;
};

int run_info(const InfoArgs& args) {
  const auto sequence = open_sequence(args.dir, parse_dataset_format(args.format));
  const Sequence& seq = *sequence;
  fmt::print("dataset:       {} ({})\n", seq.path().string(), to_string(seq.format()));
  fmt::print("name:          {}\n", seq.name());
  const double span = seq.timestamp(seq.size() - 1) - seq.timestamp(0);
  fmt::print("frames:        {} over {:.3f} s", seq.size(), span);
  if (seq.size() > 1 && span > 0.0) fmt::print(" ({:.2f} Hz)", static_cast<double>(seq.size() - 1) / span);
  fmt::print("\n");

  const auto& calib = seq.calibration();
  const SensorSet& sensors = seq.sensors();
  static constexpr const char* kCameraNames[4] = {"grey left", "grey right", "colour left", "colour right"};
  for (int c = 0; c < 4; ++c) {
    if (!sensors.cameras[static_cast<std::size_t>(c)]) continue;
    const CameraCalibration cam = calib.camera(c);
    const Eigen::Vector3d t = cam.T_cam_cam0.translation();
    fmt::print(
        "camera {}:      {:<12} {}x{}  fx {:.4f} fy {:.4f} cx {:.4f} cy {:.4f}  T_cam_cam0 t = ({:.4f}, {:.4f}, "
        "{:.4f}) m\n",
        c, kCameraNames[c], cam.camera.width, cam.camera.height, cam.camera.fx, cam.camera.fy, cam.camera.cx,
        cam.camera.cy, t.x(), t.y(), t.z());
  }
  if (sensors.lidar) {
    const Eigen::Vector3d t = calib.T_cam0_lidar.translation();
    const Eigen::Isometry3d T_lidar_cam0 = calib.T_cam0_lidar.inverse();
    LoadOptions lidar_only;
    lidar_only.cameras = {false, false, false, false};
    lidar_only.depth = false;
    const std::size_t points = seq.load(0, lidar_only).scan.size();
    fmt::print(
        "lidar:         {} points in frame 0; T_cam0_lidar t = ({:.4f}, {:.4f}, {:.4f}) m; cam0 sits at "
        "({:.3f}, {:.3f}, {:.3f}) m in the LiDAR frame\n",
        points, t.x(), t.y(), t.z(), T_lidar_cam0.translation().x(), T_lidar_cam0.translation().y(),
        T_lidar_cam0.translation().z());
  } else {
    fmt::print("lidar:         none\n");
  }
  fmt::print("depth camera:  {}\n", sensors.depth ? "yes (metres)" : "none");
  if (const auto& gt = seq.ground_truth()) {
    const double length = gt->empty() ? 0.0 : trajectory_distances(gt->poses).back();
    fmt::print("ground truth:  {} poses (T_world_cam0), path {:.2f} m\n", gt->size(), length);
  } else {
    fmt::print("ground truth:  none\n");
  }
  for (const auto& note : seq.notes()) fmt::print("note:          {}\n", note);

  if (args.check) {
    const std::vector<LoadProblem> problems = check_sequence(seq);
    for (const LoadProblem& p : problems) fmt::print("check:         frame {}: {}\n", p.frame, p.message);
    if (!problems.empty()) {
      std::size_t bad_frames = 0;  // problems come in frame order
      for (std::size_t k = 0; k < problems.size(); ++k) bad_frames += (k == 0 || problems[k].frame != problems[k - 1].frame) ? 1 : 0;
      throw Error(fmt::format("{}: {} file(s) of {} of the {} frames do not load (listed above), the first: {}",
                              seq.path().string(), problems.size(), bad_frames, seq.size(), problems.front().message));
    }
    fmt::print("check:         all {} frames load\n", seq.size());
  }
  return 0;
}

}  // namespace

Command add_info_command(CLI::App& parent) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* app = parent.add_subcommand("info",
                                        "Show what rgbl sees in a dataset folder: frames, sensors, "
                                        "calibration, image sizes, ground truth");
  app->add_option("dir", args->dir,
                  "Dataset folder: a KITTI odometry sequence (sequences/NN), a KITTI raw drive "
                  "(<date>/<date>_drive_NNNN_sync) or a TUM RGB-D folder")
      ->required();
  app->add_option("--format", args->format, "Dataset layout")
      ->check(CLI::IsMember({"auto", "kitti", "kitti-raw", "tum"}))
      ->capture_default_str();
  app->add_flag("--check", args->check, "Also load every frame (finds missing, truncated or corrupt files)");
  return {app, [args] { return run_info(*args); }};
}

}  // namespace rgbl::cli
