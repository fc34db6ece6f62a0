#include "rgbl/pipeline/demo.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/sim/path.hpp"
#include "rgbl/sim/scenarios.hpp"

#include <fmt/format.h>

#include <cmath>

namespace rgbl {

void DemoOptions::validate() const {
  if (scenario.empty() && !parse_path_kind(path)) throw ConfigError("path", "straight, curve, loop or turn");
  require(frames >= 0, "frames", ">= 0 (0: the default)");
  require(laps >= 1, "laps", ">= 1");
  if (laps != 1 && (!scenario.empty() || path != "loop")) {
    throw ConfigError("laps", "1 except on the loop path (the other paths and the scenarios do not come back)");
  }
  if (lap_offset != 0.0 && laps < 2) {
    throw ConfigError("lap_offset", "0 unless a loop of 2 or more laps is driven (the offset is the later laps')");
  }
  // the simulator's own bounds, named by the demo's keys
  require(std::isfinite(lidar_elevation_offset_deg) && std::abs(lidar_elevation_offset_deg) <= 2.0,
          "lidar_elevation_offset_deg", "an angle within +-2 deg");
  require(std::isfinite(lidar_beam_error_deg) && lidar_beam_error_deg >= 0.0 && lidar_beam_error_deg <= 2.0,
          "lidar_beam_error_deg", "a sigma in [0, 2] deg");
  // refused before any generation time is spent on it
  if (builtin_depth_sources().entry(depth).needs.depth_image) {
    throw ConfigError("depth", fmt::format("lidar[:...], stereo or precomputed[:<dir>] for the demo's KITTI layout "
                                           "(it has no depth-camera images; `precomputed` reads the exact depth), "
                                           "not '{}'",
                                           depth));
  }
}

SyntheticOptions demo_simulation(const DemoOptions& options) {
  options.validate();
  SyntheticOptions sim;
  if (!options.scenario.empty()) {
    sim = scenario_options(options.scenario, options.seed, options.frames);  // throws naming "scenario"
  } else {
    sim.frames = options.frames > 0 ? options.frames : (options.path == "loop" ? 80 * options.laps : 60);
    sim.seed = options.seed;
    sim.path.kind = *parse_path_kind(options.path);
  }
  sim.depth_camera = 0;  // the exact depth of the camera the pipeline tracks
  sim.lidar.elevation_offset_deg = options.lidar_elevation_offset_deg;
  sim.lidar.beam_elevation_sigma_deg = options.lidar_beam_error_deg;
  if (sim.path.kind == PathKind::loop) {
    fit_loop(sim, options.laps);
    sim.path.loop_lap_offset = options.lap_offset;
  }
  const DepthSourceNeeds needs = builtin_depth_sources().entry(options.depth).needs;
  sim.cameras = {true, needs.right_image, false, false};
  sim.render_depth = options.depth == "precomputed";
  sim.validate();
  return sim;
}

PipelineOptions demo_pipeline(const DemoOptions& options, const KittiLayout& layout) {
  options.validate();
  PipelineOptions pipeline;
  pipeline.dataset = layout.sequence_dir;
  pipeline.format = DatasetFormat::kitti;
  pipeline.depth = options.depth == "precomputed" ? "precomputed:" + (layout.sequence_dir / "depth").string()
                                                  : options.depth;
  pipeline.threaded = options.threaded;
  pipeline.loop_closing = options.loop_closing;
  return pipeline;
}

}  // namespace rgbl
