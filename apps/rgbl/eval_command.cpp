// rgbl eval <estimate> <ground-truth>: KITTI odometry metric, ATE, RPE and end-point drift.
#include "command.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/pipeline/compare.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

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
  fmt::print("{}", comparison_text(c));
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
