// rgbl info <dir>: what the loader sees in a dataset folder.
#include "command.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/pipeline/describe.hpp"

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
  fmt::print("{}", describe_sequence(seq));
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
