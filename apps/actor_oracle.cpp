// rgbl_actor_oracle --scenario NAME [--seeds "1 2 3"] [--frames N] [--config settings.yaml]
// How much of a scenario's error its moving vehicles cause, measured with the simulator's exact
// knowledge of where they are. Each seed is tracked three ways with the default pipeline (LiDAR
// depth, camera 0, one frame thread, so the runs are reproducible):
//   as is       the scenario as `rgbl demo --scenario NAME` tracks it;
//   no actors   the keypoints on a vehicle and the LiDAR returns from one removed before tracking:
//               what a perfect moving-object rejection would leave;
//   no traffic  the same street and drive rendered without the vehicles (nothing occluded).
// The gap between "no actors" and "no traffic" is what the vehicles cost by hiding the static street
// (fewer keypoints and depths on it), the gap between "as is" and "no actors" what their own
// keypoints and returns cost. Prints one markdown row per seed (docs/accuracy.md).
#include "rgbl/pipeline/demo.hpp"
#include "rgbl/pipeline/pipeline.hpp"
#include "rgbl/sim/sim_sequence.hpp"
#include "rgbl/tracking/frame_builder.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cmath>
#include <exception>
#include <string>
#include <vector>

namespace {

enum class Mode { as_is, no_actors, no_traffic };

// A keypoint is on a vehicle when the ray through it or through a pixel 2 px away hits one first:
// its descriptor's patch then sees the vehicle.
bool on_actor(const rgbl::SyntheticGenerator& generator, int frame, const rgbl::PinholeCamera& camera,
              const rgbl::Keypoint& keypoint) {
  const Eigen::Isometry3d T_world_cam = generator.pose(frame);
  const auto statics = static_cast<std::uint32_t>(generator.scene().objects().size());
  constexpr int kOffsets[5][2] = {{0, 0}, {-2, 0}, {2, 0}, {0, -2}, {0, 2}};
  for (const auto& [dx, dy] : kOffsets) {
    const Eigen::Vector3d ray_cam((keypoint.x + dx - camera.cx) / camera.fx, (keypoint.y + dy - camera.cy) / camera.fy, 1.0);
    const auto hit = generator.intersect(frame, T_world_cam.translation(), (T_world_cam.linear() * ray_cam).normalized(),
                                         1000.0);
    if (hit && hit->object >= statics && hit->object != rgbl::StreetScene::kGround) return true;
  }
  return false;
}

// Whether a LiDAR return (LiDAR frame) lies on one of the boxes, with a margin for the range noise.
bool in_boxes(const std::vector<rgbl::SceneObject>& boxes, const Eigen::Vector3d& p_world) {
  constexpr double kMargin = 0.15;  // m
  for (const rgbl::SceneObject& b : boxes) {
    const double dx = p_world.x() - b.cx, dy = p_world.y() - b.cy, dz = p_world.z() - b.cz;
    const double along = dx * b.ax + dz * b.az, across = -dx * b.az + dz * b.ax;
    if (std::abs(along) <= b.hx + kMargin && std::abs(dy) <= b.hy + kMargin && std::abs(across) <= b.hz + kMargin) {
      return true;
    }
  }
  return false;
}

// Keeps the keypoints for which keep[i] holds, with everything stored per keypoint.
void keep_keypoints(rgbl::Frame& frame, const std::vector<bool>& keep, const rgbl::PinholeCamera& camera) {
  rgbl::Frame kept = frame;
  kept.keypoints.clear();
  kept.descriptors.clear();
  kept.depth.clear();
  kept.depth_sigma.clear();
  kept.landmarks.clear();
  kept.outlier.clear();
  kept.moving.clear();
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!keep[i]) continue;
    kept.keypoints.push_back(frame.keypoints[i]);
    kept.descriptors.push_back(frame.descriptors[i]);
    kept.depth.push_back(frame.depth[i]);
    kept.depth_sigma.push_back(frame.depth_sigma[i]);
    if (i < frame.landmarks.size()) kept.landmarks.push_back(frame.landmarks[i]);
    if (i < frame.outlier.size()) kept.outlier.push_back(frame.outlier[i]);
    if (i < frame.moving.size()) kept.moving.push_back(frame.moving[i]);
  }
  kept.build_grid(camera.width, camera.height);
  frame = std::move(kept);
}

struct Outcome {
  double ate_m = 0.0;
  double actor_keypoints = 0.0;  // per frame, removed (no actors) or present (as is)
  double actor_returns = 0.0;    // per frame, share of the scan
  double keypoints_with_depth = 0.0;  // per frame, after the removal
};

// out: where the run's outputs go (rgbl run's files), empty for none
Outcome track(const rgbl::SyntheticOptions& scenario, Mode mode, const std::filesystem::path& config,
              const std::filesystem::path& out) {
  rgbl::SyntheticOptions rendered = scenario;
  if (mode == Mode::no_traffic) rendered.actors.clear();  // the street's layout does not depend on them
  const rgbl::SyntheticGenerator truth(scenario);         // where the vehicles are (nothing rendered)
  rgbl::PipelineOptions options;
  options.threads = 1;
  options.format = rgbl::DatasetFormat::kitti;
  options.settings = config;
  const rgbl::Pipeline pipeline(rgbl::make_synthetic_sequence(rendered), options);
  const rgbl::PinholeCamera& camera = pipeline.calibration().camera;
  rgbl::System system(pipeline.system_options(), pipeline.calibration());
  rgbl::FrameBuilder builder(pipeline.calibration(), pipeline.system_options().depth_noise, pipeline.make_depth_source(),
                             pipeline.make_extractor(), nullptr, pipeline.system_options().tracker.scan_sample);
  std::vector<rgbl::FrameRecord> records;
  Outcome outcome;
  for (std::size_t i = 0; i < pipeline.frame_count(); ++i) {
    const int frame = static_cast<int>(i);
    const rgbl::FrameInput input = pipeline.sequence().load(pipeline.frame_index(i));
    rgbl::SensorFrame sensor = pipeline.sensor_frame(input);
    std::vector<rgbl::LidarPoint> static_returns;
    if (mode != Mode::no_traffic) {
      const std::vector<rgbl::SceneObject> boxes = truth.actor_boxes(frame);
      const Eigen::Isometry3d T_world_lidar = truth.pose(frame) * truth.calibration().T_cam0_lidar;
      for (const rgbl::LidarPoint& p : sensor.scan) {
        if (!in_boxes(boxes, T_world_lidar * Eigen::Vector3d(p.x, p.y, p.z))) static_returns.push_back(p);
      }
      outcome.actor_returns += 1.0 - static_cast<double>(static_returns.size()) / std::max<std::size_t>(1, sensor.scan.size());
      if (mode == Mode::no_actors) sensor.scan = rgbl::PointCloudView(static_returns);
    }
    rgbl::PreparedFrame prepared = builder.build(sensor);
    if (mode != Mode::no_traffic) {
      std::vector<bool> keep(prepared.frame.size());
      for (std::size_t k = 0; k < keep.size(); ++k) {
        keep[k] = !on_actor(truth, frame, camera, prepared.frame.keypoints[k]);
        if (!keep[k]) outcome.actor_keypoints += 1.0;
      }
      if (mode == Mode::no_actors) keep_keypoints(prepared.frame, keep, camera);
    }
    for (const float sigma : prepared.frame.depth_sigma) outcome.keypoints_with_depth += sigma > 0.0F ? 1.0 : 0.0;
    rgbl::FrameRecord record;
    record.result = system.track(sensor, std::move(prepared));
    records.push_back(record);
  }
  system.finish();
  const rgbl::RunResult result = pipeline.collect(system, std::move(records));
  if (!out.empty()) rgbl::write_run_outputs(result, out);
  const double n = static_cast<double>(std::max<std::size_t>(1, pipeline.frame_count()));
  outcome.ate_m = result.metrics ? result.metrics->evaluation.ate.translation.rmse : std::nan("");
  outcome.actor_keypoints /= n;
  outcome.actor_returns /= n;
  outcome.keypoints_with_depth /= n;
  return outcome;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"How much of a scenario's ATE its moving vehicles cause (the simulator's exact knowledge of them)"};
  std::string scenario;
  std::vector<std::uint64_t> seeds{1, 2, 3};
  int frames = 0;
  std::filesystem::path config;
  app.add_option("--scenario", scenario, "A scenario with vehicles (rgbl demo --scenario list)")->required();
  app.add_option("--seeds", seeds, "Seeds to track")->expected(1, -1);
  app.add_option("--frames", frames, "Frames (0: the scenario's own)");
  app.add_option("--config", config, "A settings YAML, as for rgbl run");
  std::filesystem::path out;
  app.add_option("--out", out, "Write each run's outputs (as rgbl run) to OUT/seed<N>-<as-is|no-actors|no-traffic>");
  CLI11_PARSE(app, argc, argv);
  try {
    fmt::print("| {} seed | as is: ATE m | vehicle keypoints / frame | vehicle returns | no actors: ATE m | "
               "keypoints with depth / frame | no traffic: ATE m | keypoints with depth / frame |\n",
               scenario);
    fmt::print("|---|---|---|---|---|---|---|---|\n");
    for (const std::uint64_t seed : seeds) {
      rgbl::DemoOptions demo;
      demo.scenario = scenario;
      demo.seed = seed;
      demo.frames = frames;
      const rgbl::SyntheticOptions options = rgbl::demo_simulation(demo);
      const auto run_dir = [&](const char* mode) {
        return out.empty() ? out : out / fmt::format("seed{}-{}", seed, mode);
      };
      const Outcome as_is = track(options, Mode::as_is, config, run_dir("as-is"));
      const Outcome no_actors = track(options, Mode::no_actors, config, run_dir("no-actors"));
      const Outcome no_traffic = track(options, Mode::no_traffic, config, run_dir("no-traffic"));
      fmt::print("| {} | {:.3f} | {:.0f} | {:.0f} % | {:.3f} | {:.0f} | {:.3f} | {:.0f} |\n", seed, as_is.ate_m,
                 as_is.actor_keypoints, 100.0 * as_is.actor_returns, no_actors.ate_m, no_actors.keypoints_with_depth,
                 no_traffic.ate_m, no_traffic.keypoints_with_depth);
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_actor_oracle: {}\n", e.what());
    return 1;
  }
  return 0;
}
