#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/pipeline/demo.hpp"
#include "rgbl/pipeline/describe.hpp"
#include "rgbl/pipeline/pipeline.hpp"
#include "rgbl/sim/sim_sequence.hpp"
#include "rgbl/sim/synthetic.hpp"
#include "support/data.hpp"
#include "support/temp_dir.hpp"
#include "support/thread_counts.hpp"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <stop_token>
#include <utility>

using Catch::Matchers::Contains;

namespace {

// 40 frames of a curve with exact ground truth, camera 0 and the LiDAR only.
rgbl::KittiLayout write_curve(const std::filesystem::path& root) {
  rgbl::SyntheticOptions o;
  o.frames = 40;
  o.path.kind = rgbl::PathKind::curve;
  o.cameras = {true, false, false, false};
  o.render_depth = false;
  return rgbl::write_kitti(rgbl::SyntheticGenerator(o), root, 0);
}

// CTest runs each test case in a process of its own, and rendering the curve in each cost 4.4 s apiece
// (24 s under ASan). So the fixture test below writes it once per CTest run into $RGBL_PIPELINE_CURVE,
// and every test reads it there; the binary run by hand renders its own into a temporary folder.
const rgbl::KittiLayout& curve() {
  static std::optional<rgbl::test::TempDir> own;
  static const rgbl::KittiLayout layout = [] {
    if (const char* shared = std::getenv("RGBL_PIPELINE_CURVE"); shared != nullptr && *shared != '\0') {
      if (std::filesystem::exists(shared)) return rgbl::kitti_layout(shared, 0);  // the fixture's, whole
    }
    own.emplace();
    return write_curve(own->path());
  }();
  return layout;
}

rgbl::PipelineOptions options() {
  rgbl::PipelineOptions o;
  o.dataset = curve().sequence_dir;
  return o;
}

}  // namespace

// Hidden ([.]): CTest runs it as the setup of the fixture pipeline_curve (tests/pipeline/CMakeLists.txt).
TEST_CASE("fixture: the curve every pipeline test reads is written once", "[.fixture]") {
  const char* shared = std::getenv("RGBL_PIPELINE_CURVE");
  REQUIRE(shared != nullptr);
  // written beside it and renamed, so the folder exists only whole
  const std::filesystem::path folder = shared, partial = folder.string() + ".partial";
  std::filesystem::remove_all(folder);
  std::filesystem::remove_all(partial);
  write_curve(partial);
  std::filesystem::rename(partial, folder);
  CHECK(rgbl::open_sequence(rgbl::kitti_layout(folder, 0).sequence_dir)->size() == 40);
}

TEST_CASE("a pipeline tracks a sequence, re-expresses it in the ground truth's world and evaluates it") {
  auto o = options();
  o.first = 4;
  o.step = 2;
  const rgbl::Pipeline pipeline(o);
  REQUIRE(pipeline.frame_count() == 18);  // frames 4, 6, ..., 38
  CHECK(pipeline.depth_name() == "lidar");
  CHECK(pipeline.camera() == 0);
  std::vector<std::size_t> progress;
  const rgbl::RunResult run = pipeline.run([&](const rgbl::FrameRecord& r, std::size_t done, std::size_t total) {
    CHECK(total == 18);
    CHECK(r.result.frame_index == 4 + 2 * (done - 1));
    progress.push_back(done);
  });
  CHECK(progress.size() == 18);
  REQUIRE(run.frames.size() == 18);
  CHECK(run.frames.back().result.frame_index == 38);
  CHECK(run.count(rgbl::TrackState::Ok) == 18);
  REQUIRE(run.trajectory.poses.size() == 18);
  REQUIRE(run.ground_truth.size() == 18);
  // the first pose is the ground truth's at frame 4 exactly: the world is the ground truth's
  CHECK((run.trajectory.poses[0].matrix() - run.ground_truth[0].matrix()).norm() < 1e-9);
  REQUIRE(run.metrics.has_value());
  CHECK(run.metrics->frames_with_ground_truth == 18);
  CHECK(run.metrics->evaluation.ate.translation.rmse < 0.15);
  // every frame tracked: the tracked frames' figure is the whole run's
  CHECK(run.tracked_count() == 18);
  CHECK(run.metrics->frames_tracked == 18);
  REQUIRE(run.metrics->tracked_ate.has_value());
  CHECK(run.metrics->tracked_ate->translation.rmse == run.metrics->evaluation.ate.translation.rmse);
  CHECK(run.metrics->kitti_lengths == rgbl::describe_lengths(run.metrics->evaluation.kitti_options));
  CHECK(run.keyframe_count() >= 2);
  CHECK(run.landmarks.size() > 100);
  CHECK(run.keyframes.size() == run.keyframe_count());
  REQUIRE(run.min_inliers_ok().has_value());
  CHECK(*run.min_inliers_ok() >= 30);
  CHECK(run.timings().total.median > 0.0);
  // the summary people read carries the same figures
  const std::string text = rgbl::summary_text(run);
  CHECK_THAT(text, Catch::Contains("ok 18, weak 0, lost 0, not initialised 0"));
  CHECK_THAT(text, Catch::Contains(fmt::format("ATE RMSE {:.3f} m", run.metrics->evaluation.ate.translation.rmse)));
  CHECK_THAT(text, Catch::Contains(fmt::format("{} keyframes", run.keyframe_count())));

  // inline runs are reproducible to the bit
  const rgbl::RunResult again = pipeline.run();
  for (std::size_t i = 0; i < run.trajectory.poses.size(); ++i) {
    CHECK(run.trajectory.poses[i].matrix() == again.trajectory.poses[i].matrix());
  }

  rgbl::test::TempDir out;
  rgbl::write_run_outputs(run, out.path() / "run");
  for (const auto& name : rgbl::run_output_files()) CHECK(std::filesystem::exists(out.path() / "run" / name));
  const auto summary = nlohmann::json::parse(rgbl::test::read_file(out.path() / "run" / "summary.json"));
  CHECK(summary["frames"] == 18);
  CHECK(summary["first_frame"] == 4);
  CHECK(summary["step"] == 2);
  CHECK(summary["depth"] == "lidar");
  CHECK(summary["metrics"]["ate_rmse_m"].get<double>() == Approx(run.metrics->evaluation.ate.translation.rmse));
  CHECK(summary["metrics"]["frames_tracked"] == 18);
  CHECK(summary["metrics"]["tracked"]["ate_rmse_m"].get<double>() == Approx(run.metrics->evaluation.ate.translation.rmse));
  CHECK(summary["stage_ms"]["total"]["median"].get<double>() > 0.0);
  CHECK(summary["loop_closures"].is_array());
  CHECK(summary["min_inliers_ok"] == *run.min_inliers_ok());
  // 18 rows, each a 3x4 pose; row 0 is the ground truth's frame 4
  const std::string rows = rgbl::test::read_file(out.path() / "run" / "trajectory_kitti.txt");
  CHECK(std::count(rows.begin(), rows.end(), '\n') == 18);
  rgbl::remove_run_outputs(out.path() / "run");
  for (const auto& name : rgbl::run_output_files()) CHECK_FALSE(std::filesystem::exists(out.path() / "run" / name));
}

TEST_CASE("a sequence described as `rgbl info` prints it: its frames, sensors and ground truth") {
  const auto seq = rgbl::open_sequence(curve().sequence_dir);
  const std::string text = rgbl::describe_sequence(*seq);
  CHECK_THAT(text, Catch::Contains(fmt::format("frames:        {} over", seq->size())));
  CHECK_THAT(text, Catch::Contains("camera 0:      grey left"));
  CHECK_THAT(text, Catch::Contains(fmt::format("lidar:         {} points in frame 0", seq->load(0).scan.size())));
  CHECK_THAT(text, Catch::Contains(fmt::format("ground truth:  {} poses", seq->size())));
  CHECK_THAT(text, !Catch::Contains("scan times:"));  // the simulator's scans are the images' own
  if (const auto raw = rgbl::test::find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync")) {
    CHECK_THAT(rgbl::describe_sequence(*rgbl::open_sequence(*raw)),
               Catch::Contains("scan times:    frame 0's image 16.7 ms after its scan faced forward"));
  }
}

TEST_CASE("the settings file's LiDAR occlusion keys reach the LiDAR source") {
  rgbl::test::TempDir dir;
  dir.write("occ.yaml", "%YAML:1.0\nLiDAR.OcclusionWindowDeg: 0\nLiDAR.OcclusionRatio: 1.5\n");
  auto o = options();
  CHECK(rgbl::Pipeline(o).lidar_options().occlusion_window_deg == rgbl::LidarSourceOptions{}.occlusion_window_deg);
  o.settings = dir.path() / "occ.yaml";
  const rgbl::Pipeline pipeline(o);
  CHECK(pipeline.lidar_options().occlusion_window_deg == 0.0);
  CHECK(pipeline.lidar_options().occlusion_ratio == 1.5F);
  // the kernel's growth with the rings' spacing: on unless the file turns it off
  CHECK(pipeline.lidar_options().kernel_from_ring_spacing);
  o.settings = dir.write("rings.yaml", "%YAML:1.0\nLiDAR.KernelFromRingSpacing: 0\n");
  CHECK_FALSE(rgbl::Pipeline(o).lidar_options().kernel_from_ring_spacing);
  CHECK(pipeline.lidar_options().surface_step_px == 2);
  o.settings = dir.write("step.yaml", "%YAML:1.0\nLiDAR.SurfaceStepPx: 4\n");
  CHECK(rgbl::Pipeline(o).lidar_options().surface_step_px == 4);
}

TEST_CASE("the settings file's LiDAR.TimeOffset reaches the system, overriding the dataset's scan times") {
  rgbl::test::TempDir dir;
  auto o = options();
  CHECK_FALSE(rgbl::Pipeline(o).system_options().scan_time_offset);
  o.settings = dir.write("t.yaml", "%YAML:1.0\nLiDAR.TimeOffset: -0.02\n");
  CHECK(rgbl::Pipeline(o).system_options().scan_time_offset == -0.02);
  rgbl::SystemOptions bad;
  bad.scan_time_offset = 2.0;
  CHECK_THROWS_WITH(bad.validate(), Contains("scan_time_offset"));
}

TEST_CASE("the settings file's Tracking keys reach the tracker") {
  rgbl::test::TempDir dir;
  auto o = options();
  const rgbl::TrackerOptions defaults = rgbl::Pipeline(o).system_options().tracker;
  CHECK(defaults.reference_landmark_ratio == 0.25);
  CHECK(defaults.pose.bounded_depth_error);
  CHECK(defaults.register_gaps);
  CHECK(defaults.pose.cauchy);
  CHECK_FALSE(defaults.object_test);
  CHECK(defaults.register_refused_steps);
  CHECK(defaults.ransac_max_points_near_prior == 350);
  CHECK(defaults.ransac_max_points_near_prior_retry == 0);
  CHECK(defaults.ransac_max_points == 350);
  CHECK(defaults.start_doubt_s == 1.0);
  CHECK(defaults.speed_window_s == 0.3);
  CHECK(defaults.road_start);
  CHECK(defaults.start_by_rays);
  CHECK(defaults.confirm_suspect_by_scan);
  o.settings = dir.write("t.yaml", "%YAML:1.0\nTracking.ReferenceLandmarkRatio: 0\nTracking.BoundedDepthError: 0\n"
                                   "Tracking.RegisterGaps: 0\nTracking.CauchyWeights: 0\nTracking.ObjectTest: 1\n"
                                   "Tracking.RegisterRefusedSteps: 0\nTracking.RansacPointsNearPrior: 1000\n"
                                   "Tracking.RansacPointsNearPriorRetry: 1000\nTracking.StartDoubt: 0\n"
                                   "Tracking.SpeedWindow: 0\nTracking.RoadStart: 0\nTracking.StartByRays: 0\n"
                                   "Tracking.ConfirmSuspectByScan: 0\n");
  const rgbl::TrackerOptions set = rgbl::Pipeline(o).system_options().tracker;
  CHECK(set.reference_landmark_ratio == 0.0);
  CHECK_FALSE(set.pose.bounded_depth_error);
  CHECK_FALSE(set.register_gaps);
  CHECK_FALSE(set.pose.cauchy);
  CHECK(set.object_test);
  CHECK_FALSE(set.register_refused_steps);
  CHECK(set.ransac_max_points_near_prior == 1000);
  CHECK(set.ransac_max_points_near_prior_retry == 1000);
  CHECK(set.start_doubt_s == 0.0);
  CHECK(set.speed_window_s == 0.0);
  CHECK_FALSE(set.road_start);
  CHECK_FALSE(set.start_by_rays);
  CHECK_FALSE(set.confirm_suspect_by_scan);
  CHECK_FALSE(rgbl::Pipeline(o).system_options().mapping.depth_consistency);
  CHECK_FALSE(rgbl::Pipeline(o).system_options().mapping.triangulation);
  o.settings = dir.write("m.yaml", "%YAML:1.0\nLocalMapping.DepthConsistency: 1\nLocalMapping.Triangulation: 1\n");
  CHECK(rgbl::Pipeline(o).system_options().mapping.depth_consistency);
  CHECK(rgbl::Pipeline(o).system_options().mapping.triangulation);
}

TEST_CASE("the settings file's LiDAR pair sigmas and elevation correction reach local mapping and the scan samples") {
  rgbl::test::TempDir dir;
  auto o = options();
  const rgbl::KeyframePairOptions defaults = rgbl::Pipeline(o).system_options().mapping.pairs;
  CHECK(defaults.lidar_sigma_translation == 0.02);
  CHECK(defaults.lidar_sigma_rotation == 0.002);
  CHECK(defaults.lidar_agreeing_sigma_translation == 0.01);
  o.settings = dir.write("t.yaml", "%YAML:1.0\nLocalMapping.LidarPairSigma: 0\nLocalMapping.LidarPairSigmaRotation: "
                                   "0.001\nLocalMapping.LidarPairAgreeingSigma: 0.005\n");
  const rgbl::KeyframePairOptions set = rgbl::Pipeline(o).system_options().mapping.pairs;
  CHECK(set.lidar_sigma_translation == 0.0);
  CHECK(set.lidar_sigma_rotation == 0.001);
  CHECK(set.lidar_agreeing_sigma_translation == 0.005);
  CHECK(rgbl::Pipeline(o).system_options().tracker.scan_sample.elevation_correction_deg == 0.0);
  o.settings = dir.write("e.yaml", "%YAML:1.0\nLiDAR.ElevationCorrection: 0.205\n");
  CHECK(rgbl::Pipeline(o).system_options().tracker.scan_sample.elevation_correction_deg == 0.205);
}

TEST_CASE("a run that tracks nothing says so in its metrics: no figure for tracked frames") {
  // 100 features leave fewer keypoints with depth than initialisation needs: no frame is tracked
  rgbl::test::TempDir dir;
  dir.write("few.yaml", "%YAML:1.0\nORBextractor.nFeatures: 100\n");
  auto o = options();
  o.frames = 6;
  o.settings = dir.path() / "few.yaml";
  const rgbl::RunResult run = rgbl::Pipeline(o).run();
  CHECK(run.count(rgbl::TrackState::NotInitialised) == 6);
  CHECK(run.tracked_count() == 0);
  REQUIRE(run.metrics.has_value());
  CHECK(run.metrics->frames_with_ground_truth == 6);
  CHECK(run.metrics->frames_tracked == 0);
  CHECK_FALSE(run.metrics->tracked_ate.has_value());
  // the all-frames figure is that of the guesses: the start pose held (5 frames of 1 m)
  CHECK(run.metrics->evaluation.path_length == Approx(5.0).margin(0.5));
  CHECK(run.metrics->evaluation.drift.percent == Approx(100.0));
  // a trajectory of guesses is no result: the outputs say why, and hold no trajectory
  CHECK(run.failed());
  rgbl::write_run_outputs(run, dir.path() / "out");
  CHECK(std::filesystem::exists(dir.path() / "out" / "summary.json"));
  CHECK(std::filesystem::exists(dir.path() / "out" / "timing.csv"));
  for (const char* name : {"trajectory_kitti.txt", "trajectory_tum.txt", "ground_truth_kitti.txt", "trajectory.svg",
                           "map.ply"}) {
    CHECK_FALSE(std::filesystem::exists(dir.path() / "out" / name));
  }
}

namespace {
// KITTI 04's first 8 frames at every `step`-th frame: the second has no velocity yet.
rgbl::RunResult every_nth_frame(const std::filesystem::path& sequence, int step) {
  rgbl::PipelineOptions o;
  o.dataset = sequence;
  o.step = step;
  o.frames = 8;
  return rgbl::Pipeline(o).run();
}

// What each of these runs must show: `frames` frames, an ATE below 0.2 m, and the second frame's
// step (the one without a velocity) the true one within `margin`.
rgbl::RunResult tracks_every_nth_frame(const std::filesystem::path& sequence, int step, std::size_t frames,
                                       double margin) {
  rgbl::RunResult run = every_nth_frame(sequence, step);
  REQUIRE(run.frames.size() == frames);
  REQUIRE(run.metrics.has_value());
  CHECK(run.metrics->evaluation.ate.translation.rmse < 0.2);
  const double estimated = (run.trajectory.poses[1].translation() - run.trajectory.poses[0].translation()).norm();
  const double truth = (run.ground_truth[1].translation() - run.ground_truth[0].translation()).norm();
  CHECK(estimated == Approx(truth).margin(margin));
  return run;
}
}  // namespace

TEST_CASE("KITTI 04 at 2.5 Hz: the second frame is placed from both starts, and no frame is ok on a wrong pose") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  // Every 4th frame: 5.3 m between frames. From the last pose the pose converges 5 m short, on
  // distant points many matches fit; the depth consensus (9 points) is too weak to be the only start.
  // Before, all 8 frames were ok with an ATE of 11.9 m (0.051 m now), the second step 0.03 m for 5.3.
  // The second frame was weak (two starts 5 m apart contradicting each other) until keypoints were
  // mapped pixel centre to pixel centre across pyramid levels (2026-11-28); now the two starts agree
  // and it is ok, on the true step. What the test guards: no frame reported ok on a wrong pose.
  const rgbl::RunResult run = tracks_every_nth_frame(*seq, 4, 8, 0.2);
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    if (run.frames[i].result.state != rgbl::TrackState::Ok) continue;
    const double error = (run.trajectory.poses[i].translation() - run.ground_truth[i].translation()).norm();
    CAPTURE(i, error);
    CHECK(error < 0.3);
  }
  CHECK(run.count(rgbl::TrackState::Ok) >= 7);
}

TEST_CASE("KITTI 04 at 1.7 Hz: a second rigid motion is another start, and the road decides between them") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  // Every 6th frame: 7.9 m between frames. The largest depth consensus (20 points) is a 2 m sideways
  // motion; the true one holds 7 points among the matches it leaves out. From the true start the
  // local map re-finds 29 points on the road against 3. Before, all 8 frames were ok with an ATE of 18.3 m
  // (0.080 m now). Since returns behind foreground edges are dropped (2026-11-28) the second frame also
  // has a weak depth consensus 2.5 m off, which the LiDAR refutes and the images favour: the frame ends
  // on the true step but weak, as contradicting evidence must leave it. What the test guards: the true
  // step, and no frame reported ok on a wrong pose: the wrong starts here are 2-8 m off, the drift at
  // this rate stays within 1 % of the distance (frame 42: 0.32 m at 57.8 m; 0.27 m before).
  const rgbl::RunResult run = tracks_every_nth_frame(*seq, 6, 8, 0.2);
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    if (run.frames[i].result.state != rgbl::TrackState::Ok) continue;
    const double error = (run.trajectory.poses[i].translation() - run.ground_truth[i].translation()).norm();
    const double distance = (run.ground_truth[i].translation() - run.ground_truth[0].translation()).norm();
    CAPTURE(i, error, distance);
    CHECK(error < std::max(0.3, 0.01 * distance));
  }
  CHECK(run.count(rgbl::TrackState::Ok) >= 7);
}

TEST_CASE("KITTI 04 at 1.4 Hz: no image start is near the true motion, the LiDAR proposes one") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  // Every 7th frame: 9.2 m between frames. The images' starts at the second frame are a near-still
  // motion and a weak consensus 2.45 m from it; the step along the camera's axis under which most
  // LiDAR returns land on the last scan is 9.1 m, and from there the local map finds the frame (26
  // points on the road against 14; 2071 LiDAR votes against 387). Without the LiDAR's start the run
  // stood still, 7 frames ok and 1 weak, ATE 21.4 m (0.094 m now).
  const rgbl::RunResult run = tracks_every_nth_frame(*seq, 7, 8, 0.3);
  CHECK(run.count(rgbl::TrackState::Lost) == 0);
}

TEST_CASE("KITTI 04 at 1.1 Hz: where the images favour standing still, the LiDAR decides between the starts") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  // Every 9th frame: 11.8 m between frames. The largest depth consensus is a motion of a few
  // centimetres (a van ahead at the ego speed, far points); the true motion is the rival. From the
  // near-still start the local map re-finds more points, 22 of them on the road against 10. Of the
  // LiDAR returns off the road, 559 land on the last frame's scan only from the near-still start,
  // 1774 only from the true one. Without the LiDAR's say all 6 frames were ok, standing still, with
  // an ATE of 20.5 m (0.081 m now).
  const rgbl::RunResult run = tracks_every_nth_frame(*seq, 9, 6, 0.3);
  CHECK(run.count(rgbl::TrackState::Lost) == 0);
}

TEST_CASE("KITTI 04 at 1.2 Hz: after a loss, no relocalisation where the car cannot be") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  // Every 8th frame: 10.5 m between frames. Frame 40 is lost (11 frame-to-frame inliers). Relocalising
  // frame 48 against the whole map, PnP places it at frame 32's place, 21.5 m short on the straight
  // road, and the local map re-finds 89 of 717 points there (12 %, just over the ratio asked). The car
  // cannot be there: braking at 1 g from 13 m/s still covers 8.5 m in the 1.67 s since frame 32 (the
  // reach allowed is 16.4 m). Refused, frame 48 starts a new map at the constant-velocity guess. Before,
  // it was reported ok 21.7 m off (ATE 8.07 m over the tracked frames).
  const rgbl::RunResult run = every_nth_frame(*seq, 8);
  REQUIRE(run.frames.size() == 7);
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    if (run.frames[i].result.state != rgbl::TrackState::Ok) continue;
    const double error = (run.trajectory.poses[i].translation() - run.ground_truth[i].translation()).norm();
    CAPTURE(i, error);
    CHECK(error < 1.0);
  }
  CHECK_FALSE(run.frames[6].result.relocalised);
}

TEST_CASE("a corner entered harder than constant velocity expects: the turn is taken on its support") {
  // The simulator's 800-frame double loop enters its first corner at frame 39: the yaw rate jumps to
  // 3.8 deg per frame, 3.2 deg off the prediction (tolerance 3) with the centre within reach. The
  // true pose holds 451 inliers; searched from the prediction, the local map finds 30 wrong matches,
  // an ok frame's support. Only the first 45 frames are rendered. When any plausible alternative won
  // (2026-11-25 to 27), here the jump came a frame late: ATE 0.100 m and the last pose 0.17 m off, now
  // 0.059 and 0.12 m (the whole double loop 0.635 -> 0.253 m). Something moving in view can fake a
  // translation (the truck of `traffic` seed 3, tests/cli), not a turn: the better supported pose wins.
  rgbl::DemoOptions demo;  // what `rgbl demo --path loop --frames 800 --laps 2` renders
  demo.path = "loop";
  demo.frames = 800;
  demo.laps = 2;
  rgbl::PipelineOptions o;
  o.frames = 45;
  o.loop_closing = false;
  const rgbl::Pipeline pipeline(rgbl::make_synthetic_sequence(rgbl::demo_simulation(demo)), o);
  const rgbl::RunResult run = pipeline.run();
  CHECK(run.count(rgbl::TrackState::Ok) == 45);
  const std::vector<std::size_t> jumps = run.frames_where([](const auto& r) { return r.jump; });
  CHECK(std::find(jumps.begin(), jumps.end(), std::size_t{39}) != jumps.end());  // the turn taken where it is
  CHECK(run.frames_where([](const auto& r) { return r.step_rejected; }).empty());
  REQUIRE(run.metrics.has_value());
  CHECK(run.metrics->evaluation.ate.translation.rmse < 0.075);
  const Eigen::Vector3d end_error = run.trajectory.poses.back().translation() - run.ground_truth.back().translation();
  CHECK(end_error.norm() < 0.15);
}

TEST_CASE("frame threads: the same trajectory for 1, 2 and 3 threads (synthetic curve)") {
  auto o = options();
  o.frames = 24;
  rgbl::test::check_thread_counts_agree(o, {2, 3});
  // 0 means the machine's threads; out-of-range counts are refused naming the option
  o.threads = 0;
  CHECK(rgbl::Pipeline(o).threads() == rgbl::TaskPool::hardware_threads());
  o.threads = -1;
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("threads") && Contains("from 1 to 256"));
}

TEST_CASE("frame threads: the same trajectory for 1, 2 and 3 threads (KITTI 04, frames 0-29)") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  rgbl::PipelineOptions o;
  o.dataset = *seq;
  o.frames = 30;
  rgbl::test::check_thread_counts_agree(o, {2, 3});
}

TEST_CASE("frame threads: the same trajectory for 1, 2 and 3 threads (KITTI raw 0009, scans moved to the images' time)") {
  // the depth of these frames is added on the tracking thread, after the previous frame's motion
  const auto dir = rgbl::test::find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync");
  if (!dir) return;
  rgbl::PipelineOptions o;
  o.dataset = *dir;
  rgbl::test::check_thread_counts_agree(o, {2, 3});
}

TEST_CASE("KITTI raw 0009, 51 frames: the scans moved to the images' time (16.9 ms later) shorten the path's excess") {
  const auto dir = rgbl::test::find_data("kitti/raw_extended/2011_09_26/2011_09_26_drive_0009_sync");
  if (!dir) return;
  const auto length = [](const std::vector<Eigen::Isometry3d>& poses, std::size_t n) {
    double sum = 0.0;
    for (std::size_t i = 1; i < n; ++i) sum += (poses[i].translation() - poses[i - 1].translation()).norm();
    return sum;
  };
  struct Result {
    double ate, path_ratio, scan_age;
  };
  const auto run_with = [&](const std::string& settings) {
    rgbl::test::TempDir tmp;
    rgbl::PipelineOptions o;
    o.dataset = *dir;
    if (!settings.empty()) o.settings = tmp.write("s.yaml", "%YAML:1.0\n" + settings);
    const rgbl::RunResult run = rgbl::Pipeline(o).run();
    CHECK(run.count(rgbl::TrackState::Ok) == 51);
    REQUIRE(run.metrics.has_value());
    const std::size_t n = run.ground_truth.size();
    return Result{run.metrics->evaluation.ate.translation.rmse,
                  length(run.trajectory.poses, n) / length(run.ground_truth, n), run.scan_age_median().value_or(-1.0)};
  };
  // the default: each scan's own timestamp (velodyne_points/timestamps.txt)
  const Result moved = run_with("");
  // LiDAR.TimeOffset overrides the dataset's times; 0: the scan taken as simultaneous with the image
  const Result simultaneous = run_with("LiDAR.TimeOffset: 0\n");
  CHECK_THAT(moved.scan_age, Catch::Matchers::WithinAbs(0.0169, 0.0003));
  CHECK(simultaneous.scan_age == 0.0);
  INFO("ATE " << moved.ate << " m against " << simultaneous.ate << " m, path / truth " << moved.path_ratio
              << " against " << simultaneous.path_ratio);
  // five feature-count samples (nFeatures 1800-2200, 2026-12-05 session 9): 0.085-0.093 m and
  // 1.0020-1.0031 against 0.096-0.106 m and 1.0032-1.0044, each sample 0.005-0.021 m and 0.0005-0.0025
  // better. The scans' pairs in local BA measure the keyframes' steps whatever the scans' time, so the
  // gain is smaller than before them (0.010-0.031 m; docs/accuracy.md, "The LiDAR's depth moved to
  // the image's time" had 0.081-0.100 against 0.096-0.118 m)
  CHECK(moved.ate < 0.095);
  CHECK(moved.path_ratio < 1.0045);
  CHECK(moved.ate < simultaneous.ate - 0.004);
  CHECK(moved.path_ratio < simultaneous.path_ratio - 0.0003);
}

TEST_CASE("the simulator as an in-memory sequence: loaded frames equal the rendered ones, the pipeline tracks it") {
  rgbl::SyntheticOptions sim;
  sim.frames = 30;
  sim.path.kind = rgbl::PathKind::curve;
  sim.cameras = {true, false, false, false};
  sim.render_depth = false;
  const rgbl::SyntheticGenerator generator(sim);
  auto sequence = rgbl::make_synthetic_sequence(sim);
  REQUIRE(sequence->size() == 30);
  CHECK(sequence->sensors().cameras[0]);
  CHECK_FALSE(sequence->sensors().cameras[2]);
  CHECK(sequence->sensors().lidar);
  CHECK_FALSE(sequence->sensors().depth);
  const rgbl::FrameInput frame = sequence->load(7);
  CHECK(cv::norm(frame.images[0], generator.render_image(7, 0), cv::NORM_INF) == 0.0);
  CHECK(frame.scan.size() == generator.render_scan(7).size());
  CHECK(frame.timestamp == generator.timestamp(7));
  REQUIRE(sequence->ground_truth().has_value());
  CHECK(sequence->ground_truth()->poses[7].matrix() == generator.pose(7).matrix());
  CHECK_THROWS_WITH(sequence->load(30), Contains("below 30"));

  rgbl::PipelineOptions o;
  o.frames = 20;
  const rgbl::Pipeline pipeline(std::move(sequence), o);
  const rgbl::RunResult run = pipeline.run();
  CHECK(run.sequence_name == "synthetic");
  CHECK(run.count(rgbl::TrackState::Ok) == 20);
  REQUIRE(run.metrics.has_value());
  CHECK(run.metrics->evaluation.ate.translation.rmse < 0.1);
  CHECK(run.frames.back().result.map_keyframes == run.keyframes.size());
  CHECK(run.frames.back().result.map_landmarks == run.landmarks.size());
}

TEST_CASE("the demo as a library: a scenario or a path, only the sensors its depth source reads, tracked end to end") {
  using Catch::Matchers::Contains;
  rgbl::DemoOptions demo;
  demo.scenario = "lead-vehicle";
  demo.seed = 3;
  demo.frames = 12;
  const rgbl::SyntheticOptions scenario = rgbl::demo_simulation(demo);
  CHECK(scenario.frames == 12);
  CHECK(scenario.seed == 3);
  CHECK(scenario.cameras == std::array<bool, 4>{true, false, false, false});  // LiDAR depth: camera 0 alone
  CHECK_FALSE(scenario.render_depth);

  rgbl::DemoOptions loop;
  loop.path = "loop";
  loop.laps = 2;
  loop.depth = "stereo";
  const rgbl::SyntheticOptions two_laps = rgbl::demo_simulation(loop);
  CHECK(two_laps.frames == 160);  // 80 per lap by default
  CHECK(two_laps.path.kind == rgbl::PathKind::loop);
  CHECK(two_laps.cameras == std::array<bool, 4>{true, true, false, false});  // stereo reads the right image
  CHECK(two_laps.path.loop_lap_offset == 0.0);
  loop.lap_offset = -3.3;
  CHECK(rgbl::demo_simulation(loop).path.loop_lap_offset == -3.3);
  CHECK(scenario.lidar.elevation_offset_deg == 0.0);  // exact beams unless asked
  CHECK(scenario.lidar.beam_elevation_sigma_deg == 0.0);
  demo.lidar_elevation_offset_deg = 0.2;
  demo.lidar_beam_error_deg = 0.05;
  const rgbl::SyntheticOptions miscalibrated = rgbl::demo_simulation(demo);
  CHECK(miscalibrated.lidar.elevation_offset_deg == 0.2);
  CHECK(miscalibrated.lidar.beam_elevation_sigma_deg == 0.05);

  // every refusal names the key, before anything is generated
  const auto refused = [](rgbl::DemoOptions o, const char* key) {
    try {
      (void)rgbl::demo_simulation(o);
      FAIL("accepted, expected a refusal naming " << key);
    } catch (const rgbl::ConfigError& e) {
      CHECK(e.key() == key);
    }
  };
  rgbl::DemoOptions bad;
  bad.path = "spiral";
  refused(bad, "path");
  bad = {};
  bad.laps = 2;  // the curve does not come back
  refused(bad, "laps");
  bad = {};
  bad.depth = "rgbd";  // the KITTI layout has no depth camera
  refused(bad, "depth");
  bad = {};
  bad.scenario = "nope";
  refused(bad, "scenario");
  bad = {};
  bad.frames = -1;
  refused(bad, "frames");
  bad = {};
  bad.lidar_elevation_offset_deg = 3.0;
  refused(bad, "lidar_elevation_offset_deg");
  bad = {};
  bad.lidar_beam_error_deg = -0.1;
  refused(bad, "lidar_beam_error_deg");
  bad = {};
  bad.path = "loop";
  bad.lap_offset = -3.3;  // one lap has no later laps
  refused(bad, "lap_offset");
  bad.laps = 2;
  bad.lap_offset = 2.0;  // into the parking lane
  refused(bad, "path.loop_lap_offset");

  // `precomputed` alone tracks with the exact depth images the generator writes
  rgbl::test::TempDir dir;
  rgbl::DemoOptions exact;
  exact.path = "straight";
  exact.frames = 12;
  exact.depth = "precomputed";
  exact.loop_closing = false;
  const rgbl::SyntheticOptions sim = rgbl::demo_simulation(exact);
  CHECK(sim.render_depth);
  const rgbl::KittiLayout layout = rgbl::write_kitti(rgbl::SyntheticGenerator(sim), dir.path(), 0);
  const rgbl::PipelineOptions options = rgbl::demo_pipeline(exact, layout);
  CHECK(options.depth == "precomputed:" + (layout.sequence_dir / "depth").string());
  CHECK_FALSE(options.loop_closing);
  const rgbl::RunResult run = rgbl::Pipeline(options).run();
  CHECK(run.count(rgbl::TrackState::Ok) == 12);
  REQUIRE(run.metrics);
  CHECK(run.metrics->evaluation.ate.translation.rmse < 0.05);
}

TEST_CASE("a pipeline refuses bad options and data it cannot use before the first frame, naming them") {
  auto o = options();
  o.camera = 1;
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("camera"));
  o = options();
  o.camera = 2;
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("has no camera 2"));
  o = options();
  o.step = 0;
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("step"));
  o = options();
  o.first = 40;
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("--first") && Contains("below 40"));
  o = options();
  o.dataset = curve().root / "nothing_here";
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("nothing_here"));
  o = options();
  o.depth = "neural";
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("'neural'") && Contains("lidar[:") && Contains("rgbd"));
  o.depth = "stereo";  // no image_1 was written
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("stereo needs camera 1"));
  o.depth = "rgbd";
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("rgbd needs depth images") && Contains("sequences/00"));
  o.depth = "lidar:hexagon3";
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("lidar:hexagon3"));
  o.depth = "precomputed:" + (curve().root / "no_depth").string();  // the folder is read per frame
  const rgbl::Pipeline lazy(o);
  CHECK_THROWS_WITH(lazy.run(), Contains("no_depth") && Contains("000000.png"));
}

TEST_CASE("a pipeline creates a user's depth source by name and checks what it needs") {
  auto sources = rgbl::builtin_depth_sources();
  int created = 0;
  sources.add("far_lidar", {{.scan = true}, "far_lidar:<metres>", [&created](std::string_view arg, const auto& context) {
                              ++created;
                              rgbl::LidarSourceOptions lidar;
                              lidar.projection.max_depth = lidar.dilation.max_depth = std::stof(std::string(arg));
                              return rgbl::make_lidar_source(lidar, context);
                            }});
  auto o = options();
  o.frames = 10;
  o.depth = "far_lidar:50";
  const rgbl::Pipeline pipeline(o, sources);
  CHECK(created == 1);  // once at construction: its options are checked before any frame
  const rgbl::RunResult run = pipeline.run();
  // with frame threads one for each frame in flight (the System then builds none), else the System's own
  CHECK(created == 1 + (pipeline.threads() > 1 ? pipeline.threads() : 1));
  CHECK(run.depth == "far_lidar");
  CHECK(run.count(rgbl::TrackState::Ok) == 10);

  sources.add("depth_camera", {{.depth_image = true}, "depth_camera", [](std::string_view, const auto& context) {
                                 return rgbl::make_rgbd_source({}, context);
                               }});
  o.depth = "depth_camera";
  CHECK_THROWS_WITH(rgbl::Pipeline(o, sources), Contains("depth_camera needs depth images"));
}

TEST_CASE("a stop requested during a run ends it before the next frame, and its outputs say they are partial") {
  const rgbl::Pipeline pipeline(options());
  REQUIRE(pipeline.frame_count() == 40);
  std::stop_source stop;
  const rgbl::RunResult run = pipeline.run(
      [&](const rgbl::FrameRecord&, std::size_t done, std::size_t) {
        if (done == 6) stop.request_stop();  // as the CLI does on Ctrl-C
      },
      stop.get_token());
  CHECK(run.stopped);
  CHECK(run.frames_planned == 40);
  REQUIRE(run.frames.size() == 6);
  CHECK(run.trajectory.poses.size() == 6);
  CHECK(run.ground_truth.size() == 6);

  rgbl::test::TempDir out;
  rgbl::write_run_outputs(run, out.path() / "run");
  const auto summary = nlohmann::json::parse(rgbl::test::read_file(out.path() / "run" / "summary.json"));
  CHECK(summary["partial"] == true);
  CHECK(summary["frames"] == 6);
  CHECK(summary["frames_planned"] == 40);
  CHECK_THAT(rgbl::test::read_file(out.path() / "run" / "trajectory.svg"), Contains("partial: stopped after 6 of 40"));

  // a run not stopped says so too
  const rgbl::RunResult whole = rgbl::Pipeline([] {
                                  auto o = options();
                                  o.frames = 3;
                                  return o;
                                }()).run();
  CHECK_FALSE(whole.stopped);
  CHECK(nlohmann::json::parse(rgbl::summary_json(whole))["partial"] == false);
}

TEST_CASE("frames fed at the recording's pace: no frame tracked before its time, the same trajectory, a stop ends the wait") {
  auto o = options();
  o.frames = 6;  // 10 Hz: the 6th frame is due 0.5 s after the first (tracking them all takes ~0.1 s)
  o.threads = 1;
  const rgbl::RunResult fast = rgbl::Pipeline(o).run();
  o.playback_rate = 1.0;
  std::vector<double> started;  // wall time at which each frame's record arrived, from the first
  rgbl::Stopwatch clock;
  const rgbl::RunResult paced = rgbl::Pipeline(o).run([&](const rgbl::FrameRecord&, std::size_t, std::size_t) {
    started.push_back(clock.elapsed_ms() / 1000.0);
  });
  REQUIRE(started.size() == 6);
  // frame i's record comes after its tracking, which started no earlier than i * 0.1 s after frame
  // 0's, itself after the clock started
  for (std::size_t i = 1; i < started.size(); ++i) CHECK(started[i] >= 0.1 * static_cast<double>(i));
  CHECK(paced.wall_s >= 0.5);
  CHECK(paced.playback_rate == 1.0);
  CHECK(nlohmann::json::parse(rgbl::summary_json(paced))["playback_rate"] == 1.0);
  // inline, pacing changes when a frame is tracked, not its pose
  REQUIRE(paced.trajectory.poses.size() == fast.trajectory.poses.size());
  for (std::size_t i = 0; i < fast.trajectory.poses.size(); ++i) {
    CHECK(paced.trajectory.poses[i].matrix() == fast.trajectory.poses[i].matrix());
  }

  // frames 1000 s apart: a stop request ends the wait at once
  o.playback_rate = 1e-4;
  std::stop_source stop;
  rgbl::Stopwatch stopping;
  const rgbl::RunResult stopped = rgbl::Pipeline(o).run(
      [&](const rgbl::FrameRecord&, std::size_t done, std::size_t) {
        if (done == 1) stop.request_stop();
      },
      stop.get_token());
  CHECK(stopped.stopped);
  CHECK(stopped.frames.size() == 1);
  CHECK(stopping.elapsed_ms() < 30000.0);

  o.playback_rate = -1.0;
  CHECK_THROWS_WITH(rgbl::Pipeline(o), Contains("playback_rate"));
}

TEST_CASE("run outputs are refused before the run when another process writes into the folder") {
  rgbl::test::TempDir out;
  const rgbl::OutputFolder held(out.path() / "run");
  const rgbl::RunResult run = rgbl::Pipeline([] {
                                auto o = options();
                                o.frames = 3;
                                return o;
                              }()).run();
  CHECK_THROWS_WITH(rgbl::write_run_outputs(run, out.path() / "run"), Contains("another rgbl process"));
  rgbl::write_run_outputs(run, held);  // the holder writes
  CHECK(std::filesystem::exists(out.path() / "run" / "summary.json"));
}
