#include "rgbl/pipeline/compare.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include "json.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

namespace rgbl {
namespace {

using detail::Json;
using detail::json_number;

Json stats_json(const ErrorStats& s) {
  return {{"rmse", json_number(s.rmse)},
          {"mean", json_number(s.mean)},
          {"median", json_number(s.median)},
          {"max", json_number(s.max)}};
}

}  // namespace

void CompareOptions::validate() const {
  require(format == "auto" || format == "kitti" || format == "tum", "--format", "auto, kitti or tum");
  for (const double l : lengths) require(l > 0.0 && std::isfinite(l), "--lengths", "lengths > 0 m");
  require(step >= 1, "--step", "at least 1 frame between segment starts");
  require(max_time_difference >= 0.0, "--max-dt", "a time difference >= 0 s");
}

namespace {

// The whole file, read once: `rgbl eval <(cmd) gt` hands over a pipe, which cannot be read twice
// (detecting the format, then parsing).
std::stringstream read_once(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw ParseError(file, 0, "is a directory (expected a KITTI or TUM trajectory)");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ParseError(file, 0, "cannot open the file (expected a KITTI or TUM trajectory)");
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ParseError(file, 0, "cannot read the file (expected a KITTI or TUM trajectory)");
  text.clear();  // an empty file sets failbit on the copy
  return text;
}

}  // namespace

std::string detect_trajectory_format(const std::filesystem::path& file) {
  std::stringstream text = read_once(file);
  return detect_trajectory_format(text, file);
}

// "kitti" (12 numbers per row) or "tum" (8), from the first data row.
std::string detect_trajectory_format(std::istream& in, const std::filesystem::path& file) {
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::size_t fields = 0;
    for (std::size_t pos = start; pos < line.size();) {
      const auto b = line.find_first_not_of(" \t\r,", pos);
      if (b == std::string::npos) break;
      ++fields;
      pos = line.find_first_of(" \t\r,", b);
      if (pos == std::string::npos) break;
    }
    if (fields == 12) return "kitti";
    if (fields == 8) return "tum";
    throw ParseError(
        file, line_no,
        fmt::format("found {} fields: expected 12 (KITTI: row-major 3x4) or 8 (TUM: t tx ty tz qx qy qz qw)", fields));
  }
  throw ParseError(file, 0, "no poses in the file");
}

TrajectoryComparison compare_trajectory_files(const std::filesystem::path& estimate,
                                              const std::filesystem::path& ground_truth,
                                              const CompareOptions& options) {
  options.validate();
  TrajectoryComparison c;
  c.estimate = estimate;
  c.ground_truth = ground_truth;
  // each file read once, then detected and parsed from memory
  std::stringstream est_text = read_once(estimate);
  std::stringstream gt_text = read_once(ground_truth);
  const auto format_of = [&](std::stringstream& text, const std::filesystem::path& file) {
    if (options.format != "auto") return options.format;
    std::string format = detect_trajectory_format(text, file);
    text.clear();
    text.seekg(0);
    return format;
  };
  const std::string est_format = format_of(est_text, estimate);
  const std::string gt_format = format_of(gt_text, ground_truth);
  if (est_format != gt_format) {
    throw Error(fmt::format("{} is a {} trajectory but {} is a {} one: convert one of them (or pass --format)",
                            estimate.string(), est_format, ground_truth.string(), gt_format));
  }
  c.format = est_format;
  std::vector<Eigen::Isometry3d> est, gt;
  if (est_format == "kitti") {
    est = read_kitti_trajectory(est_text, estimate);
    gt = read_kitti_trajectory(gt_text, ground_truth);
    c.estimated_poses = est.size();
    if (gt.size() < est.size()) {
      throw ParseError(ground_truth, 0,
                       fmt::format("has {} poses, fewer than the {} of {}", gt.size(), est.size(), estimate.string()));
    }
    if (gt.size() > est.size()) {
      c.notes.push_back(fmt::format("using the first {} of the {} ground-truth poses (KITTI files pair by row)",
                                    est.size(), gt.size()));
      gt.resize(est.size());
    }
  } else {
    const Trajectory e = read_tum_trajectory(est_text, estimate);
    const Trajectory g = read_tum_trajectory(gt_text, ground_truth);
    c.estimated_poses = e.size();
    const auto pairs = associate_timestamps(e.timestamps, g.timestamps, options.max_time_difference);
    for (const auto& [i, j] : pairs) {
      est.push_back(e.poses[i]);
      gt.push_back(g.poses[j]);
    }
    c.notes.push_back(fmt::format("associated {} of {} estimated poses with ground truth within {} s", pairs.size(),
                                  e.size(), options.max_time_difference));
  }
  if (est.size() < 2) {
    throw Error(fmt::format("{} and {}: fewer than 2 poses to compare", estimate.string(), ground_truth.string()));
  }
  KittiMetricOptions kitti = kitti_options_for_path(trajectory_distances(gt).back());
  if (!options.lengths.empty()) kitti.lengths = options.lengths;
  kitti.step_size = options.step;
  c.evaluation = evaluate_trajectory(est, gt, kitti);
  if (options.lengths.empty() && kitti.lengths != KittiMetricOptions{}.lengths) {
    c.notes.push_back(fmt::format("the ground-truth path is {:.1f} m, too short for KITTI's 100..800 m segments: "
                                  "using {} (not comparable with published KITTI figures)",
                                  c.evaluation.path_length, describe_lengths(kitti)));
  }
  return c;
}

std::string comparison_json(const TrajectoryComparison& c) {
  const TrajectoryEvaluation& e = c.evaluation;
  Json per_length = Json::array();
  for (const auto& l : e.kitti.per_length) {
    per_length.push_back({{"length", l.length},
                          {"segments", l.segments},
                          {"t_err_percent", json_number(l.t_err_percent)},
                          {"r_err_deg_per_100m", json_number(l.r_err_deg_per_100m)}});
  }
  const Json json = {{"estimate", c.estimate.generic_string()},
                     {"ground_truth", c.ground_truth.generic_string()},
                     {"format", c.format},
                     {"poses", e.poses},
                     {"path_length_m", json_number(e.path_length)},
                     {"estimated_path_length_m", json_number(e.estimated_path_length)},
                     {"kitti",
                      {{"lengths_m", e.kitti_options.lengths},
                       {"step_frames", e.kitti_options.step_size},
                       {"segments", e.kitti.segments},
                       {"t_err_percent", json_number(e.kitti.t_err_percent)},
                       {"r_err_deg_per_100m", json_number(e.kitti.r_err_deg_per_100m)},
                       {"per_length", per_length}}},
                     {"ate_m", stats_json(e.ate.translation)},
                     {"rpe_translation_m", stats_json(e.rpe.translation)},
                     {"rpe_rotation_deg", stats_json(e.rpe.rotation_deg)},
                     {"drift",
                      {{"end_error_m", json_number(e.drift.end_error)}, {"percent", json_number(e.drift.percent)}}}};
  // a path that is not UTF-8 is written with replacement characters rather than failing the report
  return json.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

std::string comparison_text(const TrajectoryComparison& c) {
  const TrajectoryEvaluation& e = c.evaluation;
  const KittiMetric& metric = e.kitti;
  std::string s;
  const auto out = std::back_inserter(s);
  fmt::format_to(out, "estimate:      {} ({}, {} poses)\n", c.estimate.string(), c.format, c.estimated_poses);
  fmt::format_to(out, "ground truth:  {} ({})\n", c.ground_truth.string(), c.format);
  for (const auto& note : c.notes) fmt::format_to(out, "note:          {}\n", note);
  fmt::format_to(out, "path length:   {:.3f} m (ground truth); the estimate's {:.3f} m\n\n", e.path_length,
                 e.estimated_path_length);
  fmt::format_to(out, "KITTI odometry metric (devkit definition: a segment every {} frames, mean over all segments)\n",
                 e.kitti_options.step_size);
  fmt::format_to(out, "  {:>10}  {:>8}  {:>10}  {:>16}\n", "length [m]", "segments", "t_err [%]", "r_err [deg/100m]");
  const auto cell = [](double v, int width) {
    return std::isfinite(v) ? fmt::format("{:>{}.4f}", v, width) : fmt::format("{:>{}}", "-", width);
  };
  for (const auto& l : metric.per_length) {
    fmt::format_to(out, "  {:>10g}  {:>8}  {}  {}\n", l.length, l.segments, cell(l.t_err_percent, 10),
                   cell(l.r_err_deg_per_100m, 16));
  }
  fmt::format_to(out, "  {:>10}  {:>8}  {}  {}\n", "all", metric.segments, cell(metric.t_err_percent, 10),
                 cell(metric.r_err_deg_per_100m, 16));
  if (metric.segments == 0) fmt::format_to(out, "  (no segment fits in the path: pass shorter --lengths)\n");
  const auto stats = [&out](const char* label, const ErrorStats& x) {
    fmt::format_to(out, "{:<41}rmse {:.4f}  mean {:.4f}  median {:.4f}  max {:.4f}\n", label, x.rmse, x.mean,
                   x.median, x.max);
  };
  fmt::format_to(out, "\n");
  stats("ATE (rigid SE3 alignment, no scale) [m]:", e.ate.translation);
  stats("RPE per frame, translation [m]:", e.rpe.translation);
  stats("RPE per frame, rotation [deg]:", e.rpe.rotation_deg);
  fmt::format_to(out, "end-point drift: {:.4f} m = {:.4f} % of the path\n", e.drift.end_error, e.drift.percent);
  return s;
}

}  // namespace rgbl
