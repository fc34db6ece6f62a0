// rgbl_sim --out <dir> [--frames N] [--seed S] [--path straight|curve|loop] [...]
// Writes a synthetic street sequence with exact ground truth in KITTI odometry layout (see
// docs/synthetic.md), so that every KITTI loader and tool runs on it unchanged.
#include "rgbl/core/timer.hpp"
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
  int sequence = 0;
  std::vector<int> untextured;
  bool quiet = false;
  app.add_option("--out", out, "dataset root to write (sequences/NN/..., poses/NN.txt)")->required();
  app.add_option("--frames", o.frames, "number of frames")->capture_default_str();
  app.add_option("--seed", o.seed, "seed of the scene and all noise")->capture_default_str();
  app.add_option("--path", path, "camera path")->check(CLI::IsMember({"straight", "curve", "loop"}))->capture_default_str();
  app.add_option("--sequence", sequence, "sequence number NN")->capture_default_str();
  app.add_option("--width", o.width, "image width (intrinsics: KITTI 04's scaled by width/1226)")->capture_default_str();
  app.add_option("--height", o.height, "image height")->capture_default_str();
  app.add_option("--speed", o.speed, "m/s")->capture_default_str();
  app.add_option("--image-noise", o.image_noise_sigma, "image noise sigma, grey levels")->capture_default_str();
  app.add_option("--lidar-noise", o.lidar.range_noise_sigma, "LiDAR range noise sigma, m")->capture_default_str();
  app.add_option("--lidar-dropout", o.lidar.dropout, "probability of a missing LiDAR return")->capture_default_str();
  app.add_option("--depth-camera", o.depth_camera, "camera of the exact depth images (0..3)")->capture_default_str();
  app.add_option("--untextured", untextured, "FIRST LAST: frames rendered with plain surfaces")->expected(2);
  app.add_option("--drop-scan", o.dropped_scans, "frames with an empty LiDAR scan")->expected(1, 1000000);
  app.add_option("--threads", o.threads, "threads per frame")->capture_default_str();
  app.add_flag("--quiet", quiet, "print only the summary");
  CLI11_PARSE(app, argc, argv);

  try {
    o.path.kind = *rgbl::parse_path_kind(path);
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
    fmt::print("wrote {} frames of a {} path ({}x{}, seed {}) to {} in {:.1f} s ({:.0f} ms per frame)\n", o.frames,
               path, o.width, o.height, o.seed, layout.sequence_dir.string(), total.elapsed_ms() / 1000.0,
               render_ms / o.frames);
    fmt::print("ground truth: {}; exact depth of camera {}: {}\n", layout.poses_file.string(), o.depth_camera,
               (layout.sequence_dir / "depth").string());
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_sim: {}\n", e.what());
    return 1;
  }
  return 0;
}
