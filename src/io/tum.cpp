// TUM RGB-D loader.
#include "file_sequence.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/io/sequence.hpp"
#include "text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace rgbl {
namespace {

namespace fs = std::filesystem;

struct ListEntry {
  double timestamp = 0.0;
  fs::path file;
};

// rgb.txt / depth.txt: "timestamp filename" per line, '#' comments; every listed file must exist.
std::vector<ListEntry> read_file_list(const fs::path& list, const fs::path& dir) {
  auto in = detail::open_for_reading(list, "'timestamp filename' per line");
  std::vector<ListEntry> entries;
  std::string line;
  std::size_t line_no = 0;
  std::error_code ec;
  while (detail::read_line(in, line, line_no)) {
    if (detail::is_comment_or_blank(line)) continue;
    const auto tokens = detail::split(line);
    ListEntry e;
    if (tokens.size() != 2 || !detail::parse_double(tokens[0], e.timestamp) || !std::isfinite(e.timestamp)) {
      throw ParseError(list, line_no, "expected 'timestamp filename'");
    }
    if (!entries.empty() && e.timestamp <= entries.back().timestamp) {
      throw ParseError(list, line_no, "timestamps must increase");
    }
    e.file = dir / std::string(tokens[1]);
    if (!fs::is_regular_file(e.file, ec)) {
      throw ParseError(e.file, 0, fmt::format("missing (listed in {} line {})", list.filename().string(), line_no));
    }
    entries.push_back(std::move(e));
  }
  if (entries.empty()) throw ParseError(list, 0, "lists no images");
  return entries;
}

PinholeCamera camera_from_name(const std::string& name) {
  // The published TUM RGB-D colour intrinsics per sensor (their distortion is not modelled here).
  const auto make = [](double fx, double fy, double cx, double cy) {
    PinholeCamera cam;
    cam.fx = fx;
    cam.fy = fy;
    cam.cx = cx;
    cam.cy = cy;
    return cam;
  };
  if (name.find("freiburg1") != std::string::npos) return make(517.3, 516.5, 318.6, 255.3);
  if (name.find("freiburg2") != std::string::npos) return make(520.9, 521.0, 325.1, 249.7);
  if (name.find("freiburg3") != std::string::npos) return make(535.4, 539.2, 320.1, 247.6);
  return make(525.0, 525.0, 319.5, 239.5);  // the ROS default
}

}  // namespace

void TumOptions::validate() const {
  require(depth_factor > 0.0, "depth_factor", "a positive number of depth units per metre");
  require(max_time_difference >= 0.0, "max_time_difference", "a non-negative time in seconds");
  require(max_ground_truth_gap > 0.0, "max_ground_truth_gap", "a positive time in seconds");
  if (camera) {
    camera->validate();
    if (const auto why = camera->implausibility()) throw ConfigError("camera", *why);
  }
}

std::unique_ptr<Sequence> open_tum_rgbd(const fs::path& tum_dir, const TumOptions& tum, const LoadOptions& options) {
  tum.validate();
  std::error_code ec;
  require_input_folder(tum_dir, "a TUM RGB-D folder with rgb.txt, depth.txt, rgb/, depth/");
  fs::path dir = tum_dir.lexically_normal();
  if (!dir.has_filename()) dir = dir.parent_path();
  detail::SequenceTable table;
  table.format = DatasetFormat::tum;
  table.name = dir.filename().string();
  table.path = dir;
  table.depth_factor = tum.depth_factor;
  table.grey_from_colour = true;

  const auto rgb = read_file_list(dir / "rgb.txt", dir);
  std::vector<ListEntry> depth;
  if (fs::exists(dir / "depth.txt", ec)) depth = read_file_list(dir / "depth.txt", dir);
  table.sensors.cameras = {true, false, true, false};
  table.sensors.depth = !depth.empty();

  if (depth.empty()) {
    for (const auto& e : rgb) {
      detail::FrameFiles f;
      f.timestamp = e.timestamp;
      f.images[0] = f.images[2] = e.file;
      table.frames.push_back(std::move(f));
    }
  } else {
    std::vector<double> t_rgb, t_depth;
    for (const auto& e : rgb) t_rgb.push_back(e.timestamp);
    for (const auto& e : depth) t_depth.push_back(e.timestamp);
    for (const auto& [i, j] : associate_timestamps(t_rgb, t_depth, tum.max_time_difference)) {
      detail::FrameFiles f;
      f.timestamp = rgb[i].timestamp;
      f.images[0] = f.images[2] = rgb[i].file;
      f.depth = depth[j].file;
      table.frames.push_back(std::move(f));
    }
    if (table.frames.empty()) {
      throw ParseError(dir / "depth.txt", 0,
                       fmt::format("no depth image within {} s of any rgb image", tum.max_time_difference));
    }
    if (table.frames.size() < rgb.size()) {
      table.notes.push_back(fmt::format("{} of {} rgb images have a depth image within {} s; the others are skipped",
                                        table.frames.size(), rgb.size(), tum.max_time_difference));
    }
  }

  const auto gt_file = dir / "groundtruth.txt";
  if (fs::exists(gt_file, ec)) {
    require_input_file(gt_file, "a TUM trajectory: 't tx ty tz qx qy qz qw' per line");  // the reader takes pipes
    const Trajectory samples = read_tum_trajectory(gt_file);
    Trajectory gt;
    std::size_t k = 0;
    for (auto& f : table.frames) {
      while (k + 1 < samples.size() && samples.timestamps[k + 1] < f.timestamp) ++k;
      if (k + 1 >= samples.size() || samples.timestamps[k] > f.timestamp) continue;
      const double t0 = samples.timestamps[k], t1 = samples.timestamps[k + 1];
      if (t1 - t0 > tum.max_ground_truth_gap) continue;
      const double s = (f.timestamp - t0) / (t1 - t0);
      // Translation linear, rotation slerp: what evo and the TUM tools do.
      const Eigen::Quaterniond q0(samples.poses[k].linear()), q1(samples.poses[k + 1].linear());
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = q0.slerp(s, q1).toRotationMatrix();
      T.translation() = (1.0 - s) * samples.poses[k].translation() + s * samples.poses[k + 1].translation();
      f.T_world_cam0 = T;
      gt.timestamps.push_back(f.timestamp);
      gt.poses.push_back(T);
    }
    if (gt.poses.size() < table.frames.size()) {
      table.notes.push_back(fmt::format("ground truth covers {} of {} frames", gt.poses.size(), table.frames.size()));
    }
    table.ground_truth = std::move(gt);
  }

  PinholeCamera cam = tum.camera ? *tum.camera : camera_from_name(table.name);
  Matrix34d P = Matrix34d::Zero();
  P.leftCols<3>() = cam.K();
  table.calibration.P.fill(P);
  if (tum.camera && cam.width > 0) {
    table.calibration.width.fill(cam.width);
    table.calibration.height.fill(cam.height);
  }
  table.calibration.width[1] = table.calibration.width[3] = 0;
  table.calibration.height[1] = table.calibration.height[3] = 0;
  detail::set_image_sizes(table);
  for (const auto& note : table.notes) logger()->info("{}", note);
  return detail::make_file_sequence(std::move(table), options);
}

}  // namespace rgbl
