// Local mapping in its own thread: the tests CI also runs under ThreadSanitizer (label `threaded`,
// scripts/sanitize.sh). Keep them short: TSan makes them ~10x slower.
#include "reliability/failure_run.hpp"
#include "tracking/kitti_run.hpp"
#include "support/data.hpp"
#include "support/pose_error.hpp"
#include "support/sensor_frame.hpp"
#include "support/temp_dir.hpp"
#include "support/thread_counts.hpp"
#include "loop/mapped_drive.hpp"
#include "loop/sim_frames.hpp"

#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/place/place_recognition.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

TEST_CASE("threaded mapping: seq 04 still tracked throughout") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  rgbl::SystemOptions options;
  options.threaded_mapping = true;
  const auto s = rgbl::test::run_sequence(*sequence, 0, 51, options);
  INFO("ATE " << s.ate_rmse << " m, drift " << s.drift_percent << " %");
  CHECK(s.frames == 51);
  // Never lost. How many frames are ok rather than weak depends on scheduling, not on the code: when
  // mapping lags (a loaded machine, a sanitizer) a frame meets a map without its newest keyframes and
  // is honestly weak (31 of 51 ok under AddressSanitizer on a loaded 2-core machine), so that split is
  // not asserted here; the inline runs assert it exactly.
  CHECK(s.with_pose == 51);
  // Not bit-reproducible (keyframes depend on mapping progress): a looser bound than inline.
  CHECK(s.ate_rmse <= 0.2);
}

TEST_CASE("threaded mapping: the first keyframe's landmarks are culled as inline") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  rgbl::SystemOptions options;
  options.threaded_mapping = true;
  options.loop_closing.enabled = false;
  const rgbl::test::Mapped m = rgbl::test::map_drive(rgbl::open_kitti_odometry(*dir), 20, options);
  REQUIRE(m.system->map().keyframe_count() >= 4);
  const int unfound = rgbl::test::unfound_first_keyframe_landmarks(m.system->map(), options.mapping.min_found_ratio);
  CAPTURE(unfound);  // measured: 6 after 20 frames (339 before)
  CHECK(unfound <= 30);
}

TEST_CASE("threaded mapping: black frames and a dropped scan, every frame recorded") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  auto steps = rgbl::test::frames(0, 24);
  steps[8].drop_scan = true;
  for (std::size_t i = 12; i <= 13; ++i) steps[i].black = true;
  const auto o = rgbl::test::run(*sequence, steps, true);
  INFO(rgbl::test::states(o));
  rgbl::test::check_complete(o);
  CHECK(o.results[12].state == rgbl::TrackState::Lost);
  CHECK(o.results[13].state == rgbl::TrackState::Lost);
  CHECK(rgbl::has_pose(o.results.back().state));  // ok, or weak while mapping lags
}

TEST_CASE("threaded mapping: a jump of 20 frames starts a new map while mapping runs") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  const auto o = rgbl::test::run(*sequence, rgbl::test::jump(0, 14, 35, 44), true);
  INFO(rgbl::test::states(o));
  rgbl::test::check_complete(o);
  // too little of the map in view where the scans place frame 35: the new map starts there
  CHECK(o.results[15].new_map);
  int new_maps = 0;
  for (const auto& r : o.results) new_maps += r.new_map ? 1 : 0;
  CHECK(new_maps == 1);
  CHECK(rgbl::has_pose(o.results.back().state));  // ok, or weak while mapping lags
  // the loop thread may bridge the gap (reported with a later frame, if before the last): only that
  for (const auto& r : o.results) {
    if (r.loop_closure) CHECK(r.loop_closure->bridged);
  }
}

TEST_CASE("threaded loop closing: the two laps are closed in the loop thread and every frame follows") {
  // two laps of a 100 m loop (`rgbl demo --path loop --frames 201 --laps 2`), mapping and loop closing
  // in threads of their own: detection runs beside tracking, corrections land between frames
  rgbl::SyntheticOptions sim;
  sim.frames = 201;
  sim.path.kind = rgbl::PathKind::loop;
  sim.path.loop_laps = 2;
  sim.cameras = {true, false, false, false};
  const rgbl::SyntheticGenerator generator(sim);
  rgbl::SystemOptions options;
  options.threaded_mapping = true;
  // without the scans' keyframe pairs, as test_loop_sim's closure tests: with them the second lap
  // hardly drifts and the loop thread found no closure (47 keyframes)
  options.mapping.pairs.lidar_sigma_translation = 0.0;
  const rgbl::test::Mapped m = rgbl::test::track_frames(
      generator.calibration().camera(0), static_cast<std::size_t>(sim.frames),
      [&](std::size_t i) { return rgbl::test::render_frame(generator, static_cast<int>(i)); },
      options);
  const auto closures = m.system->loop_closures();  // after finish(): all of them
  const auto trajectory = m.system->trajectory();
  REQUIRE(trajectory.size() == 201);
  std::vector<Eigen::Isometry3d> estimate, truth;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    CHECK(rgbl::has_pose(m.results[i].state));
    estimate.push_back(trajectory[i].T_world_cam);
    truth.push_back(generator.pose(static_cast<int>(i)));
  }
  const double ate = rgbl::absolute_trajectory_error(estimate, truth).translation.rmse;
  const rgbl::LoopClosingStats stats = m.system->loop_statistics();
  std::size_t reported = 0;
  for (const auto& r : m.results) reported += r.loop_closure ? 1 : 0;
  INFO(closures.size() << " closures (" << reported << " reported by frames), " << stats.keyframes
                       << " keyframes in the loop thread, ATE " << ate << " m");
  // measured in 5 release runs: 1 closure and ATE 0.062 m in 4, 2 closures and 0.151 m in one that
  // shared the cores with a long run (inline 0.054 m; 1.438 m without loop closing)
  REQUIRE(!closures.empty());
  CHECK(stats.closures == static_cast<int>(closures.size()));
  CHECK(reported <= closures.size());  // one closed after the last frame is only in loop_closures()
  for (const auto& c : closures) {
    CHECK(c.frame_index >= 90);  // the second lap sees frame 0's place from 9 m before it (frame 91)
    // a true closure, however far apart its frames (22.6 m measured 2026-11-28): their relative pose
    // in the written trajectory agrees with the truth's, where a false one ties two places together
    const std::size_t i = c.frame_index, j = c.matched_frame_index;
    const auto [error_m, error_deg] = rgbl::test::relative_error(truth[i], truth[j], estimate[i], estimate[j]);
    CAPTURE(i, j, (truth[i].translation() - truth[j].translation()).norm(), error_m, error_deg);
    CHECK(error_m < 0.3);
    CHECK(error_deg < 1.5);
  }
  CHECK(ate < 0.3);
}

TEST_CASE("frame threads: frames built ahead on a pool, the same poses as one thread (seq 04)") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  rgbl::PipelineOptions o;
  o.dataset = *sequence;
  o.frames = 12;
  // more threads than cores: the pool's helping waits under contention
  rgbl::test::check_thread_counts_agree(o, {3});
}

TEST_CASE("frame threads: a raw drive's LiDAR depth finished on the tracking thread, the same poses as one thread") {
  // KITTI raw gives scan times: each frame's features are built ahead, its scan moved by the tracked
  // motion and projected on the tracking thread (FrameBuilder::build_ahead / finish)
  const auto drive = rgbl::test::find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync");
  if (!drive) return;
  rgbl::PipelineOptions o;
  o.dataset = *drive;
  rgbl::test::check_thread_counts_agree(o, {3});
}

namespace {
// Sequence 04's frames 0-7 and 28-33 as one sequence in `dir` (2.1 s between its 8th and 9th frames),
// run on 2 frame threads.
rgbl::PipelineOptions gap_excerpt(const rgbl::test::TempDir& dir, const std::filesystem::path& sequence) {
  const auto folder = dir.path() / "sequences" / "04";
  std::filesystem::create_directories(folder / "image_0");
  std::filesystem::create_directories(folder / "velodyne");
  std::filesystem::copy_file(sequence / "calib.txt", folder / "calib.txt");
  std::ifstream all_times(sequence / "times.txt");
  std::vector<std::string> times;
  for (std::string line; std::getline(all_times, line);) times.push_back(line);
  std::string kept_times;
  int k = 0;
  for (const int i : {0, 1, 2, 3, 4, 5, 6, 7, 28, 29, 30, 31, 32, 33}) {
    const std::string from = fmt::format("{:06d}", i), to = fmt::format("{:06d}", k++);
    std::filesystem::create_symlink(sequence / "image_0" / (from + ".png"), folder / "image_0" / (to + ".png"));
    std::filesystem::create_symlink(sequence / "velodyne" / (from + ".bin"), folder / "velodyne" / (to + ".bin"));
    kept_times += times.at(static_cast<std::size_t>(i)) + "\n";
  }
  dir.write("sequences/04/times.txt", kept_times);
  rgbl::PipelineOptions o;
  o.dataset = folder;
  o.threads = 2;
  return o;
}
}  // namespace

TEST_CASE("frame threads: a gap registered on the frame pool, the same poses as one thread (seq 04)") {
  // the tracker registers the scans across the gap, on the pool that builds the frames
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  const rgbl::test::TempDir dir;
  const rgbl::PipelineOptions o = gap_excerpt(dir, *sequence);
  const rgbl::RunResult run = rgbl::Pipeline(o).run();
  REQUIRE(run.frames.size() == 14);
  CHECK(run.frames[8].result.gap);
  CHECK(run.frames[8].result.gap_registered);
  rgbl::test::check_thread_counts_agree(o, {2, 3});
}

TEST_CASE("frame threads: two maps bridged on the frame pool, the same poses as one thread (seq 04)") {
  // the same gap, not registered by the tracker: it loses the frames after it and starts a new map at
  // frame 11, which the loop closer bridges to the old one by registering the scans, on the same pool
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  const rgbl::test::TempDir dir;
  rgbl::PipelineOptions o = gap_excerpt(dir, *sequence);
  o.settings = dir.write("nogaps.yaml", "%YAML:1.0\nTracking.RegisterGaps: 0\n");
  const rgbl::RunResult run = rgbl::Pipeline(o).run();
  REQUIRE(run.frames.size() == 14);
  CHECK(run.frames[8].result.state == rgbl::TrackState::Lost);
  const auto& bridged = run.frames[11].result;
  CHECK(bridged.new_map);
  REQUIRE(bridged.loop_closure);
  CHECK(bridged.loop_closure->bridged);
  rgbl::test::check_thread_counts_agree(o, {2, 3});
}

namespace {
// A recogniser of the user's that fails: its exception must reach the caller of track() or finish().
class FailingRecognizer final : public rgbl::PlaceRecognizer {
 public:
  std::string_view name() const override { return "failing"; }
  std::vector<rgbl::PlaceCandidate> query(const rgbl::PlaceQuery&, const std::function<bool(std::size_t)>&,
                                          std::size_t) const override {
    throw std::runtime_error("failing recogniser: query");
  }
  void add(const rgbl::PlaceQuery&) override { throw std::runtime_error("failing recogniser: add"); }
};
}  // namespace

TEST_CASE("threaded loop closing: an exception in the loop thread is rethrown to the caller, tracking stops cleanly") {
  rgbl::SyntheticOptions sim;
  sim.frames = 30;
  sim.cameras = {true, false, false, false};
  const rgbl::SyntheticGenerator generator(sim);
  rgbl::SystemOptions options;
  options.threaded_mapping = true;
  rgbl::DepthSourceContext depth;
  depth.calibration = generator.calibration().camera(0);
  auto system = std::make_unique<rgbl::System>(options, depth.calibration, rgbl::make_lidar_source({}, depth),
                                               rgbl::make_orb_extractor({}));
  system->add_place_recognizer(std::make_unique<FailingRecognizer>());
  std::string error;
  std::size_t tracked = 0;
  try {
    for (int i = 0; i < sim.frames; ++i) {
      const rgbl::FrameInput input = rgbl::test::render_frame(generator, i);
      system->track(rgbl::test::sensor_frame(input));
      ++tracked;
    }
    system->finish();
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  INFO(tracked << " frames tracked before the error");
  CHECK(error.starts_with("failing recogniser"));
  // the system can still be asked and destroyed (the threads stop, nothing hangs)
  CHECK(system->trajectory().size() == tracked);
  CHECK_THROWS_AS(system->add_place_recognizer(std::make_unique<FailingRecognizer>()), std::logic_error);
  CHECK_THROWS_WITH(system->finish(), Catch::Matchers::StartsWith("failing recogniser"));
  system.reset();
}

TEST_CASE("threaded mapping: a lagging mapper does not thin the map, keyframes stay as few as inline") {
  // Frames built beforehand and tracked back to back, so that local mapping lags as it does when a
  // dataset is read from disk on 2 cores. Before: local mapping created each keyframe's depth
  // landmarks, so while it lagged tracking met a thin map, made every frame a keyframe and the queue
  // grew without end (`rgbl run --threaded` on 120 frames of this street, 24 runs: ATE 0.05-2.96 m, up
  // to 57 weak frames, 57-95 keyframes where counted). Now the depth landmarks come with the keyframe and at most 3
  // keyframes wait (ORB-SLAM's cap).
  rgbl::SyntheticOptions sim;
  sim.frames = 100;
  sim.cameras = {true, false, false, false};
  sim.render_depth = false;
  const rgbl::SyntheticGenerator generator(sim);
  const rgbl::CameraCalibration calibration = generator.calibration().camera(0);
  rgbl::SystemOptions options;
  options.threaded_mapping = true;
  const rgbl::FeatureExtractor extract = rgbl::make_orb_extractor({});
  rgbl::DepthSourceContext depth;
  depth.calibration = calibration;
  rgbl::FrameBuilder builder(calibration, options.depth_noise, rgbl::make_lidar_source({}, depth), extract);
  std::vector<rgbl::SensorFrame> sensors;
  std::vector<rgbl::PreparedFrame> prepared;
  for (int i = 0; i < sim.frames; ++i) {
    const rgbl::FrameInput input = rgbl::test::render_frame(generator, i);
    rgbl::SensorFrame frame = rgbl::test::sensor_frame(input);
    prepared.push_back(builder.build(frame));
    frame.image = cv::Mat();
    frame.scan = {};  // only loop closing's scan context would use it
    sensors.push_back(frame);
  }
  rgbl::System system(options, calibration, rgbl::make_lidar_source({}, depth), extract);
  std::vector<rgbl::TrackResult> results;
  {
    // the other cores busy, as frame threads building ahead keep them in a real run
    std::vector<std::jthread> busy;
    for (unsigned k = 1; k < std::max(2U, std::thread::hardware_concurrency()); ++k) {
      busy.emplace_back([](std::stop_token stop) {
        volatile unsigned spin = 0;
        while (!stop.stop_requested()) spin = spin + 1;
      });
    }
    for (std::size_t i = 0; i < sensors.size(); ++i) results.push_back(system.track(sensors[i], std::move(prepared[i])));
  }
  system.finish();
  const auto trajectory = system.trajectory();
  REQUIRE(trajectory.size() == 100);
  std::vector<Eigen::Isometry3d> estimate, truth;
  int keyframes = 0;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    CHECK(rgbl::has_pose(results[i].state));
    keyframes += results[i].keyframe ? 1 : 0;
    estimate.push_back(trajectory[i].T_world_cam);
    truth.push_back(generator.pose(static_cast<int>(i)));
  }
  const auto ate = rgbl::absolute_trajectory_error(estimate, truth);
  INFO(keyframes << " keyframes, ATE " << ate.translation.rmse << " m");
  CHECK(keyframes <= 30);  // 13-14 here; 89-90 before, at ATE 0.7-1.6 m
  CHECK(ate.translation.rmse < 0.2);
}
