// rgbl demo [--scenario NAME|list] [--frames N] [--path straight|curve|loop] [--laps N] [--lap-offset M]
//           [--seed S] [--depth SPEC] [--out DIR] [--no-loop-closing]
//           [--keep DIR]
// The main job without a dataset: generates a synthetic street (rgbl::sim) in the KITTI odometry layout
// and tracks it through exactly the code of `rgbl run` (rgbl::Pipeline), so the accuracy
// printed is against the exact ground truth.
#include "command.hpp"
#include "input_options.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/pipeline/demo.hpp"
#include "rgbl/sim/scenarios.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>

namespace rgbl::cli {
namespace {

namespace fs = std::filesystem;

struct DemoArgs {
  DemoOptions demo;
  std::string out = "rgbl_demo_output";
  std::string keep;  // dataset folder to keep; empty = a temporary folder, removed afterwards
};

void print_scenarios() {
  for (const ScenarioInfo& s : scenarios()) {
    fmt::print("{:<14} {} (default {} frames)\n", s.name, s.description, s.default_frames);
  }
}

// The command-line option that sets DemoOptions' `key` (lap_offset: --lap-offset).
std::string option_name(const std::string& key) {
  if (key == "lidar_elevation_offset_deg") return "--lidar-elevation-offset";
  if (key == "lidar_beam_error_deg") return "--lidar-beam-error";
  std::string name = "--" + key;
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

int run_demo(const DemoArgs& args, bool quiet) {
  if (args.demo.scenario == "list") {
    print_scenarios();
    return 0;
  }
  const DemoOptions& demo = args.demo;
  SyntheticOptions sim;
  try {
    sim = demo_simulation(demo);
  } catch (const ConfigError& e) {
    throw ConfigError(option_name(e.key()), e.expected());
  }

  std::optional<TemporaryFolder> temp;
  fs::path root;
  if (args.keep.empty()) {
    temp.emplace("rgbl_demo");
    root = temp->path();
  } else {
    // a folder of its own: a KITTI root there (sequences/00, poses/00.txt) would be overwritten
    root = args.keep;
    std::error_code ec;
    if (fs::exists(root, ec) && (!fs::is_directory(root, ec) || !fs::is_empty(root, ec))) {
      throw ConfigError("--keep", fmt::format("a new or empty folder for the generated dataset ({} {})",
                                              root.string(), fs::is_directory(root, ec) ? "holds files" : "is a file"));
    }
  }
  const InterruptScope interrupt;
  // the output folder before the generation time is spent: one that cannot be written, or that another
  // run writes into, is refused now
  const OutputFolder out(args.out);

  Stopwatch generation;
  const SyntheticGenerator generator(sim);
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  const KittiLayout layout = write_kitti(generator, root, 0, [&](int i) {
    interrupt.throw_if_interrupted(args.keep.empty() ? "while generating the street (nothing written)"
                                                     : "while generating the street (" + root.string() +
                                                           " holds an incomplete dataset)");
    if (quiet) return;
    const std::string line = fmt::format("generating frame {}/{}", i + 1, sim.frames);
    if (tty) {
      fmt::print(stderr, "\r{:<70}", line);
    } else if ((i + 1) % 10 == 0 || i + 1 == sim.frames) {
      fmt::print(stderr, "{}\n", line);
    }
  });
  if (!quiet && tty) fmt::print(stderr, "\n");
  const double generation_s = generation.elapsed_ms() / 1000.0;
  fmt::print("synthetic street: {} frames of {} ({}x{}, seed {}, {:.0f} m) generated in {:.1f} s ({:.0f} ms per frame)\n",
             sim.frames, demo.scenario.empty() ? fmt::format("a {} path", demo.path) : "scenario " + demo.scenario,
             sim.width, sim.height, sim.seed, sim.driven_length(), generation_s, 1000.0 * generation_s / sim.frames);
  std::fflush(stdout);  // before the run's progress on stderr

  const RunResult run = run_and_report(Pipeline(demo_pipeline(demo, layout)), out, quiet, interrupt);

  if (temp) {
    fmt::print("  the generated dataset was removed (keep it with --keep <dir>)\n");
  } else {
    fmt::print("  dataset kept in {} (ground truth {}; track it again with `rgbl run {}`)\n", root.string(),
               layout.poses_file.string(), layout.sequence_dir.string());
  }
  if (interrupt.interrupted()) return interrupt.exit_code();  // the partial outputs are written
  // a demo that cannot track its own synthetic street is a failure worth an exit code
  return run.count(TrackState::Ok) > 0 ? 0 : 1;
}

}  // namespace

Command add_demo_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "demo", "Generate a synthetic street with exact ground truth and track it like `rgbl run` (no dataset needed)");
  auto args = std::make_shared<DemoArgs>();
  app->add_option("--frames", args->demo.frames, "Frames to generate and track (default: 60; 80 per lap of a loop, which needs >= 77 per lap; a "
                                   "scenario's own)")
      ->check(CLI::Range(2, 100000));
  auto* path = app->add_option("--path", args->demo.path, "Camera path")
                   ->check(CLI::IsMember({"straight", "curve", "loop"}))
                   ->capture_default_str();
  app->add_option("--scenario", args->demo.scenario,
                  "A stress scenario instead of --path (`--scenario list` prints them; `plain` is the reference)")
      ->excludes(path);
  app->add_option("--seed", args->demo.seed, "Seed of the scene and all noise")->capture_default_str();
  app->add_option("--depth", args->demo.depth,
                  "Depth source as for `rgbl run`: lidar (5x5 diamond), lidar:ipbasic, lidar:diamond7, stereo, "
                  "precomputed (the exact depth images) or precomputed:<dir>")
      ->capture_default_str();
  app->add_option("--out", args->out, "Output folder of the run (trajectories, timing, summary, plot, map)")
      ->capture_default_str();
  app->add_option("--keep", args->keep, "Write the synthetic dataset to this new or empty folder and keep it "
                                        "(default: a temporary folder, removed afterwards)");
  app->add_option("--laps", args->demo.laps, "Laps of --path loop in the frames driven (2: past the start and round again)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app->add_option("--lap-offset", args->demo.lap_offset,
                  "Metres right (+) or left (-) of the first lap for the later laps of --path loop (-3.3: the "
                  "next lane to the left), reached by a lane change ending 10 m before the start")
      ->capture_default_str();
  app->add_option("--lidar-elevation-offset", args->demo.lidar_elevation_offset_deg,
                  "Every LiDAR beam fires this much higher than its nominal elevation, deg (the points keep the "
                  "nominal one; 0.2 makes the scan pairs pitch as KITTI's do)")
      ->capture_default_str();
  app->add_option("--lidar-beam-error", args->demo.lidar_beam_error_deg,
                  "Sigma of each LiDAR beam's own elevation error, deg (drawn once per beam and seed)")
      ->capture_default_str();
  app->add_flag("--threaded", args->demo.threaded, "Local mapping and loop closing in threads of their own");
  app->add_flag_callback("--no-loop-closing", [args] { args->demo.loop_closing = false; }, "Track without loop closing (to compare)");
  return {app, [args, app] {
            const bool quiet = app->get_parent()->get_option("--quiet")->as<bool>();
            return run_demo(*args, quiet);
          }};
}

}  // namespace rgbl::cli
