// rgbl_sim --out <dir> [--scenario NAME|list] [--frames N] [--seed S] [--path straight|curve|loop|turn] [...]
// Writes a synthetic street sequence with exact ground truth in KITTI odometry layout (see
// docs/synthetic.md), so that every KITTI loader and tool runs on it unchanged.
#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/sim/scenarios.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <exception>
#include <map>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  CLI::App app{"Generate a synthetic KITTI-like street sequence with exact ground truth"};
  rgbl::SyntheticOptions o;
  std::string out;
  std::string path = "straight";
  std::string scenario;
  int sequence = 0;
  std::vector<int> untextured;
  std::vector<int> cameras;
  bool no_depth = false;
  bool quiet = false;
  app.add_option("--out", out, "dataset root to write (sequences/NN/..., poses/NN.txt)");
  app.add_option("--scenario", scenario,
                 "a stress scenario (`list` prints them); options given explicitly override the scenario's");
  app.add_option("--frames", o.frames, "number of frames")->capture_default_str();
  app.add_option("--seed", o.seed, "seed of the scene and all noise")->capture_default_str();
  app.add_option("--path", path, "camera path")
      ->check(CLI::IsMember({"straight", "curve", "loop", "turn"}))
      ->capture_default_str();
  int laps = 1;
  app.add_option("--laps", laps, "laps of --path loop over the frames (its perimeter fitted to them, as `rgbl demo` does)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_option("--sequence", sequence, "sequence number NN")->capture_default_str();
  app.add_option("--width", o.width, "image width (intrinsics: KITTI 04's scaled by width/1226)")->capture_default_str();
  app.add_option("--height", o.height, "image height")->capture_default_str();
  app.add_option("--speed", o.speed, "m/s")->capture_default_str();
  app.add_option("--image-noise", o.image_noise_sigma, "image noise sigma, grey levels")->capture_default_str();
  app.add_option("--lidar-noise", o.lidar.range_noise_sigma, "LiDAR range noise sigma, m")->capture_default_str();
  app.add_option("--lidar-dropout", o.lidar.dropout, "probability of a missing LiDAR return")->capture_default_str();
  app.add_option("--lidar-elevation-offset", o.lidar.elevation_offset_deg,
                 "error of every LiDAR beam's elevation, deg (the points keep the nominal one)")
      ->capture_default_str();
  app.add_option("--lidar-beam-error", o.lidar.beam_elevation_sigma_deg,
                 "sigma of each LiDAR beam's own elevation error, deg (drawn once per beam and seed)")
      ->capture_default_str();
  app.add_option("--depth-camera", o.depth_camera, "camera of the exact depth images (0..3)")->capture_default_str();
  app.add_option("--untextured", untextured, "FIRST LAST: frames rendered with plain surfaces")->expected(2);
  app.add_option("--drop-scan", o.dropped_scans, "frames with an empty LiDAR scan")->expected(1, 1000000);
  app.add_option("--cameras", cameras, "render only these cameras (e.g. 0 1); default all four")
      ->expected(1, 4)
      ->check(CLI::Range(0, 3));
  app.add_flag("--no-depth", no_depth, "do not render the exact depth images");
  app.add_option("--threads", o.threads, "threads per frame")->capture_default_str();
  app.add_flag("--quiet", quiet, "print only the summary");
  CLI11_PARSE(app, argc, argv);

  try {
    if (scenario == "list") {
      for (const auto& s : rgbl::scenarios()) fmt::print("{:<14} {} ({} frames)\n", s.name, s.description, s.default_frames);
      return 0;
    }
    if (out.empty()) throw rgbl::ConfigError("--out", "a dataset root to write");
    o.path.kind = *rgbl::parse_path_kind(path);
    if (!scenario.empty()) {
      // the scenario's options, then whatever was given explicitly on top
      const rgbl::SyntheticOptions given = o;
      o = rgbl::scenario_options(scenario, o.seed, app.count("--frames") > 0 ? given.frames : 0);
      path = std::string(rgbl::to_string(o.path.kind));
      if (app.count("--path") > 0) o.path.kind = given.path.kind;
      if (app.count("--width") > 0) o.width = given.width;
      if (app.count("--height") > 0) o.height = given.height;
      if (app.count("--speed") > 0) o.speed = given.speed;
      if (app.count("--image-noise") > 0) o.image_noise_sigma = given.image_noise_sigma;
      if (app.count("--lidar-noise") > 0) o.lidar.range_noise_sigma = given.lidar.range_noise_sigma;
      if (app.count("--lidar-dropout") > 0) o.lidar.dropout = given.lidar.dropout;
      if (app.count("--lidar-elevation-offset") > 0) o.lidar.elevation_offset_deg = given.lidar.elevation_offset_deg;
      if (app.count("--lidar-beam-error") > 0) o.lidar.beam_elevation_sigma_deg = given.lidar.beam_elevation_sigma_deg;
      if (app.count("--depth-camera") > 0) o.depth_camera = given.depth_camera;
      if (app.count("--threads") > 0) o.threads = given.threads;
      o.dropped_scans = given.dropped_scans;
    }
    if (!cameras.empty()) {
      o.cameras.fill(false);
      for (const int c : cameras) o.cameras[static_cast<std::size_t>(c)] = true;
    }
    if (no_depth) o.render_depth = false;
    if (o.path.kind == rgbl::PathKind::loop) rgbl::fit_loop(o, laps);
    if (untextured.size() == 2) o.untextured = rgbl::FrameRange{untextured[0], untextured[1]};
    rgbl::Stopwatch total;
    const rgbl::SyntheticGenerator generator(o);
    rgbl::Stopwatch frame_clock;
    double render_ms = 0.0;
    const auto layout = rgbl::write_kitti(generator, out, sequence, [&](int i) {
      const double ms = frame_clock.lap_ms();
      render_ms += ms;
      if (!quiet) fmt::print("frame {:4d}/{}: {:.0f} ms (render and write)\n", i + 1, o.frames, ms);
    });
    fmt::print("wrote {} frames of {} ({}x{}, seed {}) to {} in {:.1f} s ({:.0f} ms per frame)\n", o.frames,
               scenario.empty() ? "a " + path + " path" : "scenario " + scenario, o.width, o.height, o.seed,
               layout.sequence_dir.string(), total.elapsed_ms() / 1000.0, render_ms / o.frames);
    fmt::print("ground truth: {}", layout.poses_file.string());
    if (o.render_depth) {
      fmt::print("; exact depth of camera {}: {}", o.depth_camera, (layout.sequence_dir / "depth").string());
    }
    fmt::print("\n");
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_sim: {}\n", e.what());
    return 1;
  }
  return 0;
}
