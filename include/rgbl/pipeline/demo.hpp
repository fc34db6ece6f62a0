#pragma once
// `rgbl demo` as a library: a synthetic street with exact ground truth (a stress scenario of
// rgbl/sim/scenarios.hpp, or a path) written in the KITTI odometry layout and tracked by Pipeline.
//
//   const DemoOptions demo{.scenario = "traffic", .seed = 2};
//   const KittiLayout layout = write_kitti(SyntheticGenerator(demo_simulation(demo)), folder, 0);
//   const RunResult run = Pipeline(demo_pipeline(demo, layout)).run();
#include "rgbl/pipeline/pipeline.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <cstdint>
#include <string>

namespace rgbl {

struct DemoOptions {
  std::string scenario;         // a scenario's name (scenarios()); empty: the street of `path`
  std::string path = "curve";   // straight, curve, loop or turn, without a scenario
  int frames = 0;               // 0: a scenario's own; on a path 60, or 80 per lap of a loop
  int laps = 1;                 // of a loop (2: past the start and round again)
  double lap_offset = 0.0;      // m right (+) or left (-) of the first lap for the later laps of a loop
  std::uint64_t seed = 1;       // of the scene and all noise
  // A depth spec as for PipelineOptions::depth, of a source that needs no depth camera (the layout has
  // none); `precomputed` alone tracks with the generator's exact depth images.
  std::string depth = "lidar";
  bool threaded = false;
  bool loop_closing = true;
  // The LiDAR's intrinsic calibration error (SimLidarOptions): every beam fires this much higher than
  // its nominal elevation, and each beam by its own Gaussian error of this sigma on top, while the
  // points keep the nominal elevations, as a real HDL-64's do (0.2 deg reproduces the pitch of KITTI's
  // scan pairs: docs/synthetic.md). 0 and 0: exact beams, as the accuracy suite's scenarios.
  double lidar_elevation_offset_deg = 0.0;
  double lidar_beam_error_deg = 0.0;

  // Throws ConfigError naming the key (scenario, path, frames, laps, lap_offset, depth,
  // lidar_elevation_offset_deg, lidar_beam_error_deg).
  void validate() const;
};

// The simulator's options: the scenario's or the path's street, rendering only what tracking camera 0
// with options.depth reads (the right image for stereo, the exact depth for `precomputed`; the scan
// always, as KITTI's velodyne/ folder).
SyntheticOptions demo_simulation(const DemoOptions& options);

// Tracking of the dataset the demo wrote at `layout`.
PipelineOptions demo_pipeline(const DemoOptions& options, const KittiLayout& layout);

}  // namespace rgbl
