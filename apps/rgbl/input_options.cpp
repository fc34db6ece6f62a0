#include "input_options.hpp"

#include "command.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <stop_token>

namespace rgbl::cli {
namespace {

void print_summary(const RunResult& run, const std::filesystem::path& out_dir) {
  fmt::print("\n{}", summary_text(run));
  fmt::print("  outputs in {}: {}\n", out_dir.string(),
             run.failed() ? "timing.csv summary.json (no trajectory: nothing was tracked)"
                          : "trajectory_kitti.txt trajectory_tum.txt timing.csv summary.json trajectory.svg map.ply");
}

}  // namespace

void add_input_options(CLI::App& app, PipelineOptions& options) {
  app.add_option("dir", options.dataset, "Dataset folder: KITTI odometry sequences/NN, KITTI raw drive, or TUM RGB-D")
      ->required();
  app.add_option_function<std::string>(
         "--format", [&options](const std::string& name) { options.format = parse_dataset_format(name); },
         "Dataset layout (auto detects it)")
      ->check(CLI::IsMember({"auto", "kitti", "kitti-raw", "tum"}));
  app.add_option("--camera", options.camera, "Tracked camera: 0 (grey left, the default when present) or 2 (colour left)")
      ->check(CLI::IsMember({0, 2}));
  app.add_option("--depth", options.depth,
                 "Depth source: lidar (5x5 diamond; keypoints at their surface's mean depth), lidar:dilated "
                 "(keypoints at the dilated value, as the paper), lidar:ipbasic, lidar:ipbasic-multiscale, lidar:diamond7, "
                 "precomputed:<dir>, stereo (SGBM), stereo_sparse (keypoints only), rgbd")
      ->capture_default_str();
  app.add_option("--config", options.settings, "Settings YAML (ORB-SLAM style; RGB-L LiDAR.* keys accepted)");
  app.add_option("--frames", options.frames, "Number of frames to process, >= 1 (default: all)")
      ->check(whole_number(1));
  app.add_option("--first", options.first, "First frame to process (0: the first)")->check(whole_number(0));
  app.add_option("--step", options.step, "Process every N-th frame (e.g. 2: KITTI at 5 Hz)")->check(whole_number(1));
}

RunResult run_and_report(const Pipeline& pipeline, const OutputFolder& out_dir, bool quiet,
                         const InterruptScope& interrupt) {
  remove_run_outputs(out_dir.path());  // an earlier run's files would look like this one's if it fails
  for (const auto& note : pipeline.notes()) fmt::print(stderr, "note: {}\n", note);
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  Stopwatch wall, clock;
  std::stop_source stop;
  const auto progress = [&](const FrameRecord& record, std::size_t done, std::size_t total) {
    if (interrupt.interrupted()) stop.request_stop();  // the signal handler only records the signal
    if (quiet || (clock.elapsed_ms() <= 1000.0 && done != total)) return;
    clock.restart();
    const std::string line =
        fmt::format("frame {}/{}  {}  {:.1f} ms  {:.1f} frames/s", done, total, to_string(record.result.state),
                    record.result.timing.total_ms, static_cast<double>(done) / (wall.elapsed_ms() / 1000.0));
    if (tty) {
      fmt::print(stderr, "\r{:<70}", line);
    } else {
      fmt::print(stderr, "{}\n", line);
    }
  };
  if (interrupt.interrupted()) stop.request_stop();
  const RunResult run = pipeline.run(progress, stop.get_token());
  if (!quiet && tty) fmt::print(stderr, "\n");
  if (run.stopped) {
    fmt::print(stderr, "interrupted by {} after {} of {} frames: writing the partial outputs (summary.json: "
               "\"partial\": true)\n", interrupt.signal_name(), run.frames.size(), run.frames_planned);
  }
  write_run_outputs(run, out_dir);  // a failed run: timing.csv and summary.json alone, to tell why
  print_summary(run, out_dir.path());
  if (run.failed()) {
    throw Error(fmt::format("no frame of {} was tracked ({} not initialised, {} lost); the reasons are printed "
                            "with -v, per-frame states in {}",
                            run.frames.size(), run.count(TrackState::NotInitialised), run.count(TrackState::Lost),
                            (out_dir.path() / "timing.csv").string()));
  }
  return run;
}

}  // namespace rgbl::cli
