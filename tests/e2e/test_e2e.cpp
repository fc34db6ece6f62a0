// End to end on the synthetic street (rgbl::sim): every depth source tracks a whole sequence through
// the System facade within measured bounds (docs/synthetic.md), the depth completion is graded against
// the exact depth, and an untextured stretch or dropped scans are survived.
//
// Each sequence is rendered once per test binary (function-local statics) with only the parts the
// tests use: grey images 0 and 1, the scan and cam0's exact depth.
#include "rgbl/depth/evaluation.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/geometry/projection.hpp"
#include "rgbl/io/trajectory_io.hpp"
#include "rgbl/sim/synthetic.hpp"
#include "rgbl/tracking/system.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

namespace {

struct SimFrame {
  cv::Mat left, right;  // grey cam0, cam1
  std::vector<rgbl::LidarPoint> scan;
  cv::Mat_<float> depth;  // exact, cam0
};

struct SimData {
  rgbl::SyntheticOptions options;
  rgbl::KittiCalibration calibration;
  std::vector<Eigen::Isometry3d> poses;  // T_world_cam0, first = identity
  std::vector<SimFrame> frames;
};

// The first `count` frames (all when count < 0).
SimData render(const rgbl::SyntheticOptions& options, int count = -1) {
  const rgbl::SyntheticGenerator generator(options);
  SimData data;
  data.options = options;
  data.calibration = generator.calibration();
  for (int i = 0; i < (count < 0 ? options.frames : count); ++i) {
    data.poses.push_back(generator.pose(i));
    SimFrame f;
    f.left = generator.render_image(i, 0);
    f.right = generator.render_image(i, 1);
    f.scan = generator.render_scan(i);
    f.depth = generator.render_depth(i, 0);
    data.frames.push_back(std::move(f));
  }
  return data;
}

// 30 m straight, then into a 60 degree left bend of radius 40 m.
rgbl::SyntheticOptions curve_options() {
  rgbl::SyntheticOptions o;
  o.seed = 1;
  o.frames = 60;
  o.path.kind = rgbl::PathKind::curve;
  o.depth_camera = 0;
  return o;
}

const SimData& curve_street() {
  static const SimData data = render(curve_options());
  return data;
}

rgbl::DepthSourceContext depth_context(const SimData& data) {
  rgbl::DepthSourceContext c;
  c.calibration = data.calibration.camera(0);
  c.stereo_baseline = data.calibration.baseline(0, 1);
  return c;
}

// The built-ins, with rgbd's range for a street rather than a room.
rgbl::DepthSourceRegistry street_sources() {
  auto registry = rgbl::builtin_depth_sources();
  rgbl::RgbdSourceOptions rgbd;
  rgbd.max_depth = 80.0F;
  registry.add("rgbd", rgbl::rgbd_depth_source(rgbd));
  return registry;
}

struct RunResult {
  std::vector<rgbl::TrackResult> results;
  std::vector<rgbl::TrajectoryPose> trajectory;
  std::size_t tracked = 0;
  double ate = 0.0, drift_percent = 0.0;
};

// Tracks every frame with the named source. The exact depth goes in as the frame's float depth image
// for rgbd; `source` is a --depth spec (precomputed:<folder> reads its PNGs there).
RunResult track(const SimData& data, std::unique_ptr<rgbl::DepthSource> depth, bool rgbd = false) {
  rgbl::OrbExtractor orb;
  rgbl::System system({}, data.calibration.camera(0), std::move(depth),
                      [&orb](const cv::Mat& grey, std::vector<rgbl::Keypoint>& keypoints,
                             std::vector<rgbl::Descriptor>& descriptors) { orb.extract(grey, keypoints, descriptors); });
  RunResult run;
  for (std::size_t i = 0; i < data.frames.size(); ++i) {
    const SimFrame& f = data.frames[i];
    rgbl::SensorFrame frame;
    frame.index = i;
    frame.timestamp = 0.1 * static_cast<double>(i);
    frame.image = f.left;
    frame.image_right = f.right;
    frame.scan = f.scan;
    if (rgbd) frame.depth_image = f.depth;
    run.results.push_back(system.track(frame));
    run.tracked += run.results.back().state == rgbl::TrackState::Ok ? 1 : 0;
  }
  system.finish();
  run.trajectory = system.trajectory();
  std::vector<Eigen::Isometry3d> estimate;
  for (const auto& p : run.trajectory) estimate.push_back(p.T_world_cam);
  if (estimate.size() == data.poses.size()) {
    run.ate = rgbl::absolute_trajectory_error(estimate, data.poses).translation.rmse;
    run.drift_percent = rgbl::end_point_drift(estimate, data.poses).percent;
  }
  return run;
}

RunResult track(const SimData& data, const std::string& source) {
  return track(data, street_sources().create(source, depth_context(data)), source == "rgbd");
}

void report(const std::string& name, const RunResult& run, std::size_t frames) {
  fmt::print("e2e {:<22} tracked {:3d}/{:3d}  ATE {:.3f} m  drift {:.2f} %\n", name, run.tracked, frames, run.ate,
             run.drift_percent);
}

}  // namespace

TEST_CASE("every depth source tracks the synthetic street", "[e2e]") {
  const SimData& data = curve_street();
  const std::size_t n = data.frames.size();
  rgbl::test::TempDir temp;

  struct Case {
    std::string label, source;
    double max_ate_m, max_drift_percent;
  };
  // bounds: the figures measured with seed 1 (docs/synthetic.md) with a margin
  const std::vector<Case> cases{
      {"lidar (diamond5)", "lidar", 0.30, 1.5},     {"lidar:ipbasic", "lidar:ipbasic", 0.40, 2.0},
      {"stereo (SGBM)", "stereo", 0.65, 3.0},       {"rgbd (exact depth)", "rgbd", 0.20, 0.8},
      {"precomputed (exact)", "precomputed", 0.15, 0.6},
  };
  for (const auto& c : cases) {
    DYNAMIC_SECTION(c.label) {
      std::string spec = c.source;
      if (c.source == "precomputed") {
        const auto folder = temp.path() / "depth";
        std::filesystem::create_directories(folder);
        for (std::size_t i = 0; i < n; ++i) {
          rgbl::write_depth_png(folder / fmt::format("{:06d}.png", i), data.frames[i].depth);
        }
        spec = "precomputed:" + folder.string();
      }
      const RunResult run = track(data, spec);
      report(c.label, run, n);
      REQUIRE(run.trajectory.size() == n);
      CHECK(run.results.front().state == rgbl::TrackState::Ok);  // depth from the first frame: initialised at once
      CHECK(run.tracked == n);
      CHECK(run.ate < c.max_ate_m);
      CHECK(run.drift_percent < c.max_drift_percent);
    }
  }
}

TEST_CASE("the 5x5 diamond against the exact depth", "[e2e][depth]") {
  // only the scans and the exact depth of every 5th frame of the curve
  const rgbl::SyntheticGenerator generator(curve_options());
  rgbl::DepthSourceContext settings;
  settings.calibration = generator.calibration().camera(0);
  const auto diamond = rgbl::make_lidar_source({}, settings);
  rgbl::LidarSourceOptions ip_options;
  ip_options.completion = rgbl::CompletionMethod::ip_basic_fast;
  const auto ip_basic = rgbl::make_lidar_source(ip_options, settings);
  rgbl::DepthErrorAccumulator sparse_errors, diamond_errors, ip_basic_errors;
  for (int i = 0; i < generator.frame_count(); i += 5) {
    const std::vector<rgbl::LidarPoint> scan = generator.render_scan(i);
    const cv::Mat_<float> exact = generator.render_depth(i, 0);
    rgbl::SensorFrame frame;
    frame.index = static_cast<std::size_t>(i);
    frame.scan = scan;
    diamond->prepare(frame);
    ip_basic->prepare(frame);
    // the projected scan alone: what the completion starts from
    cv::Mat_<float> sparse(settings.calibration.camera.height, settings.calibration.camera.width, 0.0F);
    rgbl::project_to_depth(scan, settings.calibration.P_img_lidar(), rgbl::ProjectionOptions{}, sparse);
    sparse_errors.add(sparse, exact);
    diamond_errors.add(diamond->dense_depth(), exact);
    ip_basic_errors.add(ip_basic->dense_depth(), exact);
  }
  const auto print = [](const char* name, const rgbl::DepthErrors& e) {
    fmt::print("e2e depth {:<10} coverage {:.3f}  MAE {:.3f} m  RMSE {:.3f} m  iMAE {:.2f} 1/km  iRMSE {:.2f} 1/km\n",
               name, e.coverage, e.mae, e.rmse, e.imae, e.irmse);
  };
  const auto s = sparse_errors.result();
  const auto d = diamond_errors.result();
  const auto ip = ip_basic_errors.result();
  print("sparse", s);
  print("diamond5", d);
  print("ip_basic", ip);
  // Measured with seed 1 (every 5th frame of the curve): sparse coverage 0.158, MAE 0.21 m, RMSE 1.82 m;
  // diamond5 0.567, 0.51 m, 2.57 m; IP-Basic 0.599, 0.68 m, 3.09 m. The RMSE is dominated by depth
  // edges: the LiDAR sits 33 cm behind the camera and sees background the camera does not.
  CHECK(s.coverage > 0.12);
  CHECK(s.coverage < 0.20);
  CHECK(s.mae < 0.3);
  CHECK(s.rmse < 2.5);
  // the diamond fills 13 pixels around each sample: ~3.5x the coverage, errors at depth edges
  CHECK(d.coverage > 0.50);
  CHECK(d.coverage < 0.65);
  CHECK(d.mae < 0.7);
  CHECK(d.rmse < 3.5);
  CHECK(d.imae < 3.0);
  CHECK(d.irmse < 14.0);
  CHECK(ip.coverage > d.coverage);
}

namespace {

// Whole run survived: a state for every frame, a trajectory pose for every frame, and the poses
// written as a KITTI trajectory file read back with as many lines.
void check_survived(const SimData& data, const RunResult& run, int first_bad, int last_bad) {
  const std::size_t n = data.frames.size();
  REQUIRE(run.results.size() == n);
  REQUIRE(run.trajectory.size() == n);
  for (std::size_t i = 0; i < n; ++i) {
    CHECK(run.results[i].frame_index == i);
    CHECK(run.trajectory[i].frame_index == i);
  }
  rgbl::test::TempDir temp;
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& p : run.trajectory) poses.push_back(p.T_world_cam);
  rgbl::write_kitti_trajectory(temp.path() / "trajectory.txt", poses);
  CHECK(rgbl::read_kitti_trajectory(temp.path() / "trajectory.txt").size() == n);
  // tracking before the trouble
  for (int i = 0; i < first_bad; ++i) CHECK(run.results[static_cast<std::size_t>(i)].state == rgbl::TrackState::Ok);
  std::string states;
  for (const auto& r : run.results) {
    switch (r.state) {
      case rgbl::TrackState::Ok: states += 'o'; break;
      case rgbl::TrackState::Weak: states += 'w'; break;
      case rgbl::TrackState::Lost: states += 'L'; break;
      case rgbl::TrackState::NotInitialised: states += 'n'; break;
    }
  }
  fmt::print("e2e states {} (trouble in frames {}..{})\n", states, first_bad, last_bad);

}

}  // namespace

TEST_CASE("an untextured stretch is survived", "[e2e]") {
  static const SimData data = [] {
    rgbl::SyntheticOptions o;
    o.seed = 2;
    o.frames = 40;
    o.depth_camera = 0;
    o.untextured = rgbl::FrameRange{15, 22};
    return render(o);
  }();
  const RunResult run = track(data, "lidar");
  report("untextured 15..22", run, data.frames.size());
  check_survived(data, run, 15, 22);
  // Plain surfaces still have corners (object outlines, shading of faces, markings' edges): ORB finds
  // ~1100 instead of ~1950 keypoints there and tracking holds (measured: 40/40 with a pose, ATE
  // 0.06 m); the first plain frame finds too few local-map points (the map holds textured corners) and
  // is honestly weak, every other frame ok.
  for (int i = 15; i <= 22; ++i) CHECK(run.results[static_cast<std::size_t>(i)].keypoints < 1500);
  std::size_t weak = 0;
  for (std::size_t i = 0; i < run.results.size(); ++i) {
    const auto state = run.results[i].state;
    CHECK(rgbl::has_pose(state));
    if (state == rgbl::TrackState::Weak) {
      ++weak;
      CHECK(i >= 15);  // only from the trouble on
      CHECK(i <= 23);
    }
  }
  CHECK(weak <= 2);
  CHECK(run.tracked + weak == data.frames.size());
  CHECK(run.ate < 0.15);
}

TEST_CASE("a blank camera is survived: lost, then relocalised", "[e2e]") {
  SimData data = render(curve_options(), 40);  // frames 20..24 see nothing at all
  for (int i = 20; i <= 24; ++i) {
    data.frames[static_cast<std::size_t>(i)].left = cv::Mat(data.frames[0].left.size(), CV_8UC1, cv::Scalar(128));
    data.frames[static_cast<std::size_t>(i)].right = data.frames[static_cast<std::size_t>(i)].left;
  }
  const RunResult run = track(data, "lidar");
  report("blank camera 20..24", run, data.frames.size());
  check_survived(data, run, 20, 24);
  // nothing to see: lost, reported as such; relocalised on the map at the first image again
  // (measured: frame 25, then tracked to the end; ATE 0.14 m)
  for (int i = 20; i <= 24; ++i) CHECK(run.results[static_cast<std::size_t>(i)].state == rgbl::TrackState::Lost);
  for (std::size_t i = 27; i < run.results.size(); ++i) CHECK(run.results[i].state == rgbl::TrackState::Ok);
  CHECK(run.tracked >= 33);
  CHECK(run.ate < 0.3);
}

TEST_CASE("dropped scans are survived", "[e2e]") {
  static const SimData data = [] {
    rgbl::SyntheticOptions o;
    o.seed = 3;
    o.frames = 40;
    o.depth_camera = 0;
    o.dropped_scans = {15, 20, 21, 22};
    return render(o);
  }();
  const RunResult run = track(data, "lidar");
  report("dropped scans", run, data.frames.size());
  check_survived(data, run, 15, 22);
  // frames without depth are tracked on the map alone (measured: 40/40, ATE 0.06 m)
  for (const int i : data.options.dropped_scans) CHECK(run.results[static_cast<std::size_t>(i)].keypoints_with_depth == 0);
  CHECK(run.tracked == data.frames.size());
  CHECK(run.ate < 0.15);
}

TEST_CASE("a 16-beam LiDAR starts the map and tracks", "[e2e]") {
  // Every fourth of the HDL-64-like beams (1.5 deg apart in the upper block) at KITTI's resolution, the
  // rings 21 px apart in the image (docs/accuracy.md, "Sparser LiDARs"). With the paper's 5x5 diamond
  // alone the first frame holds fewer keypoints with depth than the 300 initialisation once asked for,
  // and no frame was tracked; now it starts (measured: 251 on frame 0, 30 of 30 frames ok, ATE
  // 0.012 m). By default the kernel grows with the rings' spacing (to 21 here) and gives more
  // keypoints depth (measured: 1107 on frame 0), but on this street it tracks worse (ATE 0.055 m): the
  // simulator's rings are straight, their samples 3 px apart along an image row, so the surface under a
  // grown kernel stops at the first gap and a keypoint gets the depth of the ring's end nearest the
  // camera. Steps of 4 columns (LiDAR.SurfaceStepPx: 4) mend that (measured: ATE 0.012 m). On KITTI thinned
  // to 16 rings the grown kernel wins (over five samples 1.46 and 0.77 m with the 5x5 diamond, 0.048 and
  // 0.116 m grown) and steps of 4 do not (docs/accuracy.md, "A ring's samples 3 px apart").
  static const SimData data = [] {
    rgbl::SyntheticOptions o = curve_options();
    o.seed = 2;
    o.frames = 30;
    o.width = 1226;  // KITTI's own resolution: the rings as many pixels apart as on KITTI
    o.height = 370;
    o.lidar.beams = 16;
    return render(o);
  }();
  rgbl::LidarSourceOptions diamond;
  diamond.kernel_from_ring_spacing = false;
  const RunResult fixed = track(data, rgbl::make_lidar_source(diamond, depth_context(data)));
  const RunResult grown = track(data, "lidar");
  rgbl::LidarSourceOptions long_steps;
  long_steps.surface_step_px = 4;
  const RunResult stepped = track(data, rgbl::make_lidar_source(long_steps, depth_context(data)));
  for (const auto& [name, run] : {std::pair{"16 beams, 5x5", &fixed}, std::pair{"16 beams, grown", &grown},
                                  std::pair{"16 beams, grown, steps of 4", &stepped}}) {
    report(name, *run, data.frames.size());
    fmt::print("  frame 0: {} keypoints with depth\n", run->results.front().keypoints_with_depth);
    CHECK(run->results.front().state == rgbl::TrackState::Ok);
    CHECK(run->tracked == data.frames.size());
  }
  CHECK(fixed.ate < 0.03);
  CHECK(grown.ate < 0.1);
  CHECK(stepped.ate < 0.03);
  // what the test is about: sparser than the old initialisation asked, and more with the grown kernel
  CHECK(fixed.results.front().keypoints_with_depth < 300);
  CHECK(grown.results.front().keypoints_with_depth > 2 * fixed.results.front().keypoints_with_depth);
}
