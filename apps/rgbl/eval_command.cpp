// rgbl eval <estimate> <ground-truth>: KITTI odometry metric, ATE, RPE and end-point drift.
#include "command.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/pipeline/compare.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace rgbl::cli {
namespace {

namespace fs = std::filesystem;

struct EvalArgs {
  fs::path estimate;
  fs::path ground_truth;
  CompareOptions options;
  std::string json;
};

int run_eval(const EvalArgs& args) {
  const TrajectoryComparison c = compare_trajectory_files(args.estimate, args.ground_truth, args.options);
  const TrajectoryEvaluation& e = c.evaluation;
  const KittiMetric& metric = e.kitti;
  const AteResult& ate = e.ate;
  const RpeResult& rpe = e.rpe;
  const DriftResult& drift = e.drift;
  fmt::print("estimate:      {} ({}, {} poses)\n", args.estimate.string(), c.format, c.estimated_poses);
  fmt::print("ground truth:  {} ({})\n", args.ground_truth.string(), c.format);
  for (const auto& note : c.notes) fmt::print("note:          {}\n", note);
  fmt::print("path length:   {:.3f} m\n\n", e.path_length);
  fmt::print("KITTI odometry metric (devkit definition: a segment every {} frames, mean over all segments)\n",
             e.kitti_options.step_size);
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

  if (args.json == "-") {
    fmt::print("{}", comparison_json(c));
  } else if (!args.json.empty()) {
    // written whole and renamed, so that a failure never leaves a complete-looking report
    write_atomically(args.json, [&](std::ofstream& out) { out << comparison_json(c); });
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
  app->add_option("--format", args->options.format, "Trajectory format (auto: 12 fields = kitti, 8 = tum)")
      ->check(CLI::IsMember({"auto", "kitti", "tum"}))
      ->capture_default_str();
  app->add_option("--lengths", args->options.lengths,
                  "KITTI segment lengths in metres, comma separated (default 100,...,800; for paths under 800 m up "
                  "to 8 round lengths below the path, as `rgbl run`)")
      ->delimiter(',')
      ->check(finite_number(0.0, false));
  app->add_option("--step", args->options.step, "Frames between segment starts (KITTI: 10)")
      ->check(whole_number(1))
      ->capture_default_str();
  app->add_option("--max-dt", args->options.max_time_difference, "TUM: largest timestamp difference to pair poses, s")
      ->check(finite_number(0.0, true))
      ->capture_default_str();
  app->add_option("--json", args->json, "Also write the results as JSON to this file ('-' for stdout)");
  return {app, [args] { return run_eval(*args); }};
}

}  // namespace rgbl::cli
