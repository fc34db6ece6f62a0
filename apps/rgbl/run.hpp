#pragma once
// `rgbl run`'s engine, shared with `rgbl demo`: tracks a pipeline's frames, writes the outputs and
// returns what the one-screen summary shows.

#include "pipeline.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace rgbl::cli {

struct RunOutcome {
  std::size_t frames = 0, tracked = 0, weak = 0, lost = 0, not_initialised = 0, keyframes = 0, landmarks = 0;
  std::optional<int> min_inliers_ok;  // fewest local-map inliers on a frame reported ok
  double wall_s = 0.0;
  double median_front_ms = 0.0;  // depth + extraction + tracking
  double median_total_ms = 0.0, mean_total_ms = 0.0;
  std::optional<double> ate_rmse_m, drift_percent, kitti_t_err_percent, kitti_r_err_deg_per_100m;
  std::string kitti_lengths;  // e.g. "100..800 m" or "10..60 m (short run)"
};

// Runs `pipeline` and writes trajectory_kitti.txt, trajectory_tum.txt, timing.csv, summary.json,
// trajectory.svg and map.ply into out_dir (created). Prints progress to stderr unless quiet, and the
// summary to stdout.
RunOutcome run_pipeline(Pipeline& pipeline, const std::filesystem::path& out_dir, bool threaded, bool quiet);

}  // namespace rgbl::cli
