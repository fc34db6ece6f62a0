// rgbl eval <estimate> <ground-truth>: KITTI odometry metric, ATE, RPE and end-point drift.
#include "command.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace rgbl::cli {
namespace {

namespace fs = std::filesystem;

struct EvalArgs {
  fs::path estimate;
  fs::path ground_truth;
  std::string format = "auto";
  std::vector<double> lengths;
  std::size_t step = 10;
  double max_time_difference = 0.02;
  std::string json;
};

// "kitti" (12 numbers per row) or "tum" (8), from the first data row.
std::string detect_format(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw ParseError(file, 0, "cannot open the file (expected a KITTI or TUM trajectory)");
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

using Json = nlohmann::ordered_json;

Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json stats_json(const ErrorStats& s) {
  return {{"rmse", number(s.rmse)}, {"mean", number(s.mean)}, {"median", number(s.median)}, {"max", number(s.max)}};
}

int run_eval(const EvalArgs& args) {
  const std::string est_format = args.format == "auto" ? detect_format(args.estimate) : args.format;
  const std::string gt_format = args.format == "auto" ? detect_format(args.ground_truth) : args.format;
  if (est_format != gt_format) {
    throw Error(fmt::format("{} is a {} trajectory but {} is a {} one: convert one of them (or pass --format)",
                            args.estimate.string(), est_format, args.ground_truth.string(), gt_format));
  }
  std::vector<Eigen::Isometry3d> est, gt;
  std::vector<std::string> notes;
  if (est_format == "kitti") {
    est = read_kitti_trajectory(args.estimate);
    gt = read_kitti_trajectory(args.ground_truth);
    if (gt.size() < est.size()) {
      throw ParseError(
          args.ground_truth, 0,
          fmt::format("has {} poses, fewer than the {} of {}", gt.size(), est.size(), args.estimate.string()));
    }
    if (gt.size() > est.size()) {
      notes.push_back(fmt::format("using the first {} of the {} ground-truth poses (KITTI files pair by row)",
                                  est.size(), gt.size()));
      gt.resize(est.size());
    }
  } else {
    const Trajectory e = read_tum_trajectory(args.estimate);
    const Trajectory g = read_tum_trajectory(args.ground_truth);
    const auto pairs = associate_timestamps(e.timestamps, g.timestamps, args.max_time_difference);
    for (const auto& [i, j] : pairs) {
      est.push_back(e.poses[i]);
      gt.push_back(g.poses[j]);
    }
    notes.push_back(fmt::format("associated {} of {} estimated poses with ground truth within {} s", pairs.size(),
                                e.size(), args.max_time_difference));
  }
  if (est.size() < 2) {
    throw Error(
        fmt::format("{} and {}: fewer than 2 poses to compare", args.estimate.string(), args.ground_truth.string()));
  }

  KittiMetricOptions kitti = kitti_options_for_path(trajectory_distances(gt).back());
  if (!args.lengths.empty()) kitti.lengths = args.lengths;
  kitti.step_size = args.step;
  const TrajectoryEvaluation evaluation = evaluate_trajectory(est, gt, kitti);
  const double path_length = evaluation.path_length;
  if (args.lengths.empty() && kitti.lengths != KittiMetricOptions{}.lengths) {
    notes.push_back(fmt::format("the ground-truth path is {:.1f} m, too short for KITTI's 100..800 m segments: using {} "
                                "(not comparable with published KITTI figures)",
                                path_length, describe_lengths(kitti)));
  }
  const KittiMetric& metric = evaluation.kitti;
  const AteResult& ate = evaluation.ate;
  const RpeResult& rpe = evaluation.rpe;
  const DriftResult& drift = evaluation.drift;

  fmt::print("estimate:      {} ({}, {} poses)\n", args.estimate.string(), est_format, est.size());
  fmt::print("ground truth:  {} ({})\n", args.ground_truth.string(), gt_format);
  for (const auto& note : notes) fmt::print("note:          {}\n", note);
  fmt::print("path length:   {:.3f} m\n\n", path_length);
  fmt::print("KITTI odometry metric (devkit definition: a segment every {} frames, mean over all segments)\n",
             kitti.step_size);
  fmt::print("  {:>10}  {:>8}  {:>10}  {:>16}\n", "length [m]", "segments", "t_err [%]", "r_err [deg/100m]");
  const auto cell = [](double v, int width) {
    return std::isfinite(v) ? fmt::format("{:>{}.4f}", v, width) : fmt::format("{:>{}}", "-", width);
  };
  for (const auto& l : metric.per_length) {
    fmt::print("  {:>10g}  {:>8}  {}  {}\n", l.length, l.segments, cell(l.t_err_percent, 10),
               cell(l.r_err_deg_per_100m, 16));
  }
  fmt::print("  {:>10}  {:>8}  {}  {}\n", "all", metric.segments, cell(metric.t_err_percent, 10),
             cell(metric.r_err_deg_per_100m, 16));
  if (metric.segments == 0) {
    fmt::print("  (no segment fits in the path: pass shorter --lengths)\n");
  }
  fmt::print("\nATE (rigid SE3 alignment, no scale) [m]: rmse {:.4f}  mean {:.4f}  median {:.4f}  max {:.4f}\n",
             ate.translation.rmse, ate.translation.mean, ate.translation.median, ate.translation.max);
  fmt::print("RPE per frame, translation [m]:          rmse {:.4f}  mean {:.4f}  median {:.4f}  max {:.4f}\n",
             rpe.translation.rmse, rpe.translation.mean, rpe.translation.median, rpe.translation.max);
  fmt::print("RPE per frame, rotation [deg]:           rmse {:.4f}  mean {:.4f}  median {:.4f}  max {:.4f}\n",
             rpe.rotation_deg.rmse, rpe.rotation_deg.mean, rpe.rotation_deg.median, rpe.rotation_deg.max);
  fmt::print("end-point drift: {:.4f} m = {:.4f} % of the path\n", drift.end_error, drift.percent);

  if (!args.json.empty()) {
    Json per_length = Json::array();
    for (const auto& l : metric.per_length) {
      per_length.push_back({{"length", l.length},
                            {"segments", l.segments},
                            {"t_err_percent", number(l.t_err_percent)},
                            {"r_err_deg_per_100m", number(l.r_err_deg_per_100m)}});
    }
    const Json json = {{"estimate", args.estimate.generic_string()},
                       {"ground_truth", args.ground_truth.generic_string()},
                       {"format", est_format},
                       {"poses", est.size()},
                       {"path_length_m", number(path_length)},
                       {"kitti",
                        {{"lengths_m", kitti.lengths},
                         {"step_frames", kitti.step_size},
                         {"segments", metric.segments},
                         {"t_err_percent", number(metric.t_err_percent)},
                         {"r_err_deg_per_100m", number(metric.r_err_deg_per_100m)},
                         {"per_length", per_length}}},
                       {"ate_m", stats_json(ate.translation)},
                       {"rpe_translation_m", stats_json(rpe.translation)},
                       {"rpe_rotation_deg", stats_json(rpe.rotation_deg)},
                       {"drift", {{"end_error_m", number(drift.end_error)}, {"percent", number(drift.percent)}}}};
    const std::string text = json.dump(2) + "\n";
    if (args.json == "-") {
      fmt::print("{}", text);
    } else {
      // written whole and renamed, so that a failure never leaves a complete-looking report
      write_atomically(args.json, [&](std::ofstream& out) { out << text; });
    }
  }
  return 0;
}

}  // namespace

Command add_eval_command(CLI::App& parent) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* app =
      parent.add_subcommand("eval", "Compare an estimated trajectory with ground truth: KITTI metric, ATE, RPE, drift");
  app->add_option("estimate", args->estimate, "Estimated trajectory (KITTI or TUM format)")->required();
  app->add_option("ground-truth", args->ground_truth, "Ground-truth trajectory in the same format")->required();
  app->add_option("--format", args->format, "Trajectory format (auto: 12 fields = kitti, 8 = tum)")
      ->check(CLI::IsMember({"auto", "kitti", "tum"}))
      ->capture_default_str();
  app->add_option("--lengths", args->lengths,
                  "KITTI segment lengths in metres, comma separated (default 100,...,800; for paths under 800 m up "
                  "to 8 round lengths below the path, as `rgbl run`)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  app->add_option("--step", args->step, "Frames between segment starts (KITTI: 10)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--max-dt", args->max_time_difference, "TUM: largest timestamp difference to pair poses, s")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app->add_option("--json", args->json, "Also write the results as JSON to this file ('-' for stdout)");
  return {app, [args] { return run_eval(*args); }};
}

}  // namespace rgbl::cli
