// rgbl_track_kitti <sequence dir> [--camera 0|2] [--frames N] [--output traj.txt] [--threaded]
// Runs the RGB-L system with LiDAR depth on a KITTI odometry sequence and prints accuracy (ATE after a
// rigid alignment, end-point drift) against poses/NN.txt and the median time per stage.
#include "dev/kitti_run.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <exception>

int main(int argc, char** argv) {
  CLI::App app{"Track a KITTI odometry sequence with LiDAR depth"};
  std::string sequence, output;
  rgbl::dev::RunOptions options;
  bool threaded = false;
  app.add_option("sequence", sequence, "KITTI odometry sequence folder (.../sequences/NN)")->required();
  app.add_option("--camera", options.camera, "tracked camera (0 grey, 2 colour)")->check(CLI::IsMember({0, 2}));
  app.add_option("--frames", options.frames, "number of frames (default: all)");
  app.add_option("--depth", options.depth, "depth source: lidar or stereo (needs image_<camera+1>)")
      ->check(CLI::IsMember({"lidar", "stereo"}));
  app.add_option("--output", output, "write the cam0 trajectory in KITTI format");
  app.add_flag("--threaded", threaded, "local mapping in its own thread");
  app.add_flag("--verbose", options.verbose, "one line per frame");
  bool no_ba = false, no_kf_culling = false, no_fusion = false;
  app.add_flag("--no-ba", no_ba, "disable local bundle adjustment");
  app.add_flag("--no-kf-culling", no_kf_culling, "disable keyframe culling");
  app.add_flag("--no-fusion", no_fusion, "disable duplicate fusion");
  auto& t = options.system.tracker;
  auto& dn = options.system.depth_noise;
  app.add_option("--motion-radius", t.motion_radius, "px, guided matching with the motion model");
  app.add_option("--local-radius", t.local_map_radius, "px, local-map search");
  app.add_option("--max-hamming", t.max_hamming, "Hamming threshold");
  app.add_option("--close-depth", t.close_depth, "m, depth used in pose optimisation below this");
  app.add_option("--sigma-per-pixel", dn.sigma_per_pixel, "depth noise gain per pixel to the sample");
  app.add_option("--gate-sigmas", t.depth_gate_sigmas, "depth gate in matching, sigmas (0 = off)");
  app.add_option("--gate-motion", t.depth_gate_min_motion, "m");
  app.add_option("--gate-local", t.depth_gate_min_local_map, "m");
  app.add_option("--motion-hamming", t.motion_max_hamming, "Hamming threshold, motion model");
  app.add_option("--motion-ratio", t.motion_ratio, "ratio test, motion model");
  app.add_option("--local-ratio", t.local_map_ratio, "ratio test, local map");
  bool no_ransac = false;
  app.add_flag("--no-ransac", no_ransac, "constant-velocity prediction only");
  app.add_flag("--cauchy", t.pose.cauchy, "Cauchy kernel in pose optimisation");
  app.add_option("--sigma-min", dn.sigma_min, "m, depth noise floor");
  app.add_option("--scan-period", options.system.lidar_scan_period, "s, LiDAR motion compensation (0 = off)");
  app.add_option("--spin", options.system.lidar_spin, "+1 / -1, LiDAR spin direction");
  app.add_option("--sigma-quadratic", dn.sigma_quadratic, "depth noise growing with z^2 (1/bf)");
  app.add_option("--sigma-relative", dn.sigma_relative, "depth noise relative to z");
  app.add_option("--max-spread", dn.max_spread, "m, depth-edge threshold");
  app.add_option("--max-spread-relative", dn.max_spread_relative, "depth-edge threshold relative to z");
  app.add_option("--max-sigma-relative", dn.max_sigma_relative, "drop depths with sigma above this fraction of z");
  CLI11_PARSE(app, argc, argv);
  options.system.threaded_mapping = threaded;
  t.ransac_prediction = !no_ransac;
  options.system.mapping.local_ba = !no_ba;
  options.system.mapping.keyframe_culling = !no_kf_culling;
  options.system.mapping.fusion = !no_fusion;
  try {
    const auto s = rgbl::dev::run_kitti_sequence(sequence, options);
    fmt::print("frames {}  tracked {}  lost {}  keyframes {}\n", s.frames, s.tracked, s.lost, s.keyframes);
    fmt::print("ATE RMSE {:.4f} m  end-point drift {:.3f} % of {:.2f} m  scale ratio {:.4f}\n", s.ate_rmse,
               s.drift_percent, s.path_length, s.scale_ratio);
    fmt::print("median ms: depth {:.2f}  extraction {:.2f}  tracking {:.2f}  mapping {:.2f}  "
               "depth+extraction+tracking {:.2f}  total {:.2f}; mean: mapping {:.2f}  total {:.2f}\n",
               s.median_depth_ms, s.median_extraction_ms, s.median_tracking_ms, s.median_mapping_ms,
               s.median_front_ms, s.median_total_ms, s.mean_mapping_ms, s.mean_total_ms);
    if (!output.empty()) rgbl::dev::write_kitti_trajectory(output, s.estimate);
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return 0;
}
