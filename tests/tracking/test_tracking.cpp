#include "kitti_run.hpp"
#include "reliability/failure_run.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/frame_builder.hpp"
#include "rgbl/tracking/system.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <random>
#include <stdexcept>

namespace {

// A depth source that never has depth: the tracker must stay "not initialised", never crash.
class NoDepth final : public rgbl::DepthSource {
 public:
  std::string_view name() const override { return "none"; }
  void prepare(const rgbl::SensorFrame&) override {}
  void sample(std::span<const Eigen::Vector2f>, std::span<rgbl::KeypointDepth> out) const override {
    for (auto& d : out) d = {};
  }
  cv::Mat_<float> dense_depth() const override { return {}; }
};

rgbl::CameraCalibration small_camera() {
  rgbl::CameraCalibration c;
  c.camera.fx = c.camera.fy = 300.0;
  c.camera.cx = 160.0;
  c.camera.cy = 120.0;
  c.camera.width = 320;
  c.camera.height = 240;
  return c;
}

// Frames built outside the System, as a caller with its own threads would: LiDAR depth, ORB features.
// Sequence 04's camera 0 tracked by a System without a depth source of its own: each frame is built
// outside it (LiDAR depth, ORB) and handed over.
struct BuiltSeq04 {
  std::unique_ptr<rgbl::Sequence> sequence;
  rgbl::CameraCalibration calibration;
  rgbl::SystemOptions options;
  rgbl::FrameBuilder builder;
  rgbl::System system;
  rgbl::FrameInput input;  // the loaded frame's images, which the SensorFrame views

  explicit BuiltSeq04(const std::filesystem::path& dir)
      : sequence(rgbl::open_kitti_odometry(dir)),
        calibration(sequence->calibration().camera(0)),
        builder(make_builder(calibration, options)),
        system(options, calibration) {}

  rgbl::SensorFrame load(std::size_t i) {
    input = sequence->load(i);
    rgbl::SensorFrame frame = rgbl::test::sensor_frame(input, 0);
    frame.index = i;
    return frame;
  }
  rgbl::TrackResult track(const rgbl::SensorFrame& frame) { return system.track(frame, builder.build(frame)); }

  static rgbl::FrameBuilder make_builder(const rgbl::CameraCalibration& calibration, const rgbl::SystemOptions& options) {
    rgbl::DepthSourceContext context;
    context.calibration = calibration;
    auto orb = std::make_shared<rgbl::OrbExtractor>();
    return rgbl::FrameBuilder(calibration, options.depth_noise, rgbl::make_lidar_source({}, context),
                              [orb](const cv::Mat& g, std::vector<rgbl::Keypoint>& k, std::vector<rgbl::Descriptor>& d) {
                                orb->extract(g, k, d);
                              });
  }
};

}  // namespace

TEST_CASE("keypoint grid returns exactly the keypoints inside the window and level range") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> x(0.0F, 639.0F), y(0.0F, 479.0F);
  std::vector<rgbl::Keypoint> kps(2000);
  for (std::size_t i = 0; i < kps.size(); ++i) {
    kps[i].x = x(rng);
    kps[i].y = y(rng);
    kps[i].level = static_cast<int>(i % 8);
  }
  const rgbl::FeatureGrid grid(kps, 640, 480);
  std::vector<int> out;
  for (int q = 0; q < 200; ++q) {
    const float qx = x(rng), qy = y(rng), r = 3.0F + static_cast<float>(q % 40);
    const int min_level = q % 3, max_level = q % 5 == 0 ? -1 : min_level + 2;
    grid.query(qx, qy, r, min_level, max_level, out);
    std::vector<int> expected;
    for (std::size_t i = 0; i < kps.size(); ++i) {
      if (std::abs(kps[i].x - qx) <= r && std::abs(kps[i].y - qy) <= r && kps[i].level >= min_level &&
          (max_level < 0 || kps[i].level <= max_level)) {
        expected.push_back(static_cast<int>(i));
      }
    }
    std::sort(out.begin(), out.end());
    CHECK(out == expected);
  }
}

TEST_CASE("system: configuration errors name the key, no depth keeps it uninitialised") {
  auto extractor = [](const cv::Mat&, std::vector<rgbl::Keypoint>& k, std::vector<rgbl::Descriptor>& d) {
    k.clear();
    d.clear();
  };
  CHECK_THROWS_AS(rgbl::System({}, small_camera(), nullptr, extractor), rgbl::ConfigError);
  rgbl::SystemOptions bad;
  bad.tracker.max_hamming = 0;
  CHECK_THROWS_AS(rgbl::System(bad, small_camera(), std::make_unique<NoDepth>(), extractor), rgbl::ConfigError);
  rgbl::TrackerOptions verify;
  verify.verify_min_found_ratio = 1.5;
  CHECK_THROWS_WITH(verify.validate(), Catch::Contains("tracker.verify_min_found_ratio"));
  verify = {};
  verify.verify_min_motion_ratio = -0.1;
  CHECK_THROWS_WITH(verify.validate(), Catch::Contains("tracker.verify_min_motion_ratio"));
  verify = {};
  verify.relocalisation_ransac_px = 0.0;
  CHECK_THROWS_WITH(verify.validate(), Catch::Contains("tracker.relocalisation_ransac_px"));
  verify = {};
  verify.urgent_reference_ratio = 1.5;
  CHECK_THROWS_WITH(verify.validate(), Catch::Contains("tracker.urgent_reference_ratio"));
  verify = {};
  verify.reference_landmark_ratio = -0.1;
  CHECK_THROWS_WITH(verify.validate(), Catch::Contains("tracker.reference_landmark_ratio"));

  rgbl::OrbExtractor orb;
  rgbl::System system({}, small_camera(), std::make_unique<NoDepth>(),
                      [&orb](const cv::Mat& g, std::vector<rgbl::Keypoint>& k, std::vector<rgbl::Descriptor>& d) {
                        orb.extract(g, k, d);
                      });
  cv::Mat image(240, 320, CV_8UC1);
  cv::randu(image, 0, 255);
  for (std::size_t i = 0; i < 3; ++i) {
    rgbl::SensorFrame frame;
    frame.index = i;
    frame.image = i == 1 ? cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)) : image;  // a black frame too
    const auto r = system.track(frame);
    CHECK(r.state == rgbl::TrackState::NotInitialised);
    CHECK(r.keypoints_with_depth == 0);
  }
  CHECK(system.trajectory().size() == 3);
  CHECK(system.map().keyframe_count() == 0);
}

TEST_CASE("seq 04 with LiDAR depth: every frame tracked, ATE <= 0.10 m, drift <= 0.8 %") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  // Frames 30-38 have a van ahead at the car's speed holding many of the strongest corners: without
  // the tracker's motion prior and coverage ranking this run ends 5.1 m off (docs/tracking.md).
  const auto s = rgbl::test::run_sequence(*sequence, 0, 51);
  INFO("ATE " << s.ate_rmse << " m, drift " << s.drift_percent << " %");
  CHECK(s.frames == 51);
  CHECK(s.tracked == 51);
  CHECK(s.ate_rmse <= 0.10);
  CHECK(s.drift_percent <= 0.8);
}

TEST_CASE("deterministic mode: the same input gives a bit-identical trajectory") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  const auto a = rgbl::test::run_sequence(*sequence, 2, 20);
  const auto b = rgbl::test::run_sequence(*sequence, 2, 20);
  REQUIRE(a.estimate.size() == 20);
  REQUIRE(b.estimate.size() == 20);
  for (std::size_t i = 0; i < a.estimate.size(); ++i) {
    CHECK(a.estimate[i].matrix() == b.estimate[i].matrix());
  }
  CHECK(a.tracked == 20);
  CHECK(a.ate_rmse < 0.1);
}

TEST_CASE("relocalisation neither changes nor depends on the caller's OpenCV generator") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  // Frames 0-12, then 4-6 again without a gap in the clock: frame 4 is placed by relocalisation (PnP
  // RANSAC), run here on the calling thread.
  const auto steps = rgbl::test::jump(0, 12, 4, 6, true);
  std::vector<rgbl::TrajectoryPose> first;
  for (const std::uint64_t seed : {std::uint64_t{1}, std::uint64_t{0x9e3779b97f4a7c15}}) {
    cv::theRNG().state = seed;
    const rgbl::test::Outcome o = rgbl::test::run(*sequence, steps);
    CHECK(cv::theRNG().state == seed);
    REQUIRE(o.results.size() == steps.size());
    CHECK(o.results[13].relocalised);
    if (first.empty()) {
      first = o.trajectory;
      continue;
    }
    REQUIRE(o.trajectory.size() == first.size());
    for (std::size_t i = 0; i < first.size(); ++i) {
      CHECK(o.trajectory[i].T_world_cam.matrix() == first[i].T_world_cam.matrix());
    }
  }
}

TEST_CASE("system: the camera's motion from a frame's scan to its image, from the tracked velocity") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  BuiltSeq04 t(*dir);
  rgbl::SensorFrame frame = t.load(0);
  frame.scan_timestamp = frame.timestamp - 0.017;
  CHECK(t.system.scan_moves(frame));
  CHECK(t.system.scan_motion(frame).matrix() == Eigen::Matrix4d::Identity());  // nothing tracked yet
  for (std::size_t i = 0; i < 6; ++i) REQUIRE(rgbl::has_pose(t.track(t.load(i)).state));
  frame = t.load(6);
  CHECK_FALSE(t.system.scan_moves(frame));  // the odometry format gives no scan times
  CHECK(t.system.scan_motion(frame).matrix() == Eigen::Matrix4d::Identity());
  frame.scan_timestamp = frame.timestamp - 0.017;
  CHECK_THAT(t.system.scan_age(frame), Catch::Matchers::WithinAbs(0.017, 1e-9));
  const Eigen::Isometry3d T_image_scan = t.system.scan_motion(frame);
  // the truth's step 5 -> 6 (1.33 m in 104.2 ms, 12.7 m/s along the camera's z), over 17 ms of it
  const auto& gt = t.sequence->ground_truth()->poses;
  const Eigen::Isometry3d T_6_5 = gt[6].inverse() * gt[5];
  const double share = 0.017 / (t.sequence->timestamp(6) - t.sequence->timestamp(5));
  CHECK(T_image_scan.translation().z() < -0.2);
  CHECK((T_image_scan.translation() - share * T_6_5.translation()).norm() < 0.01);
  CHECK(rgbl::rotation_angle(T_image_scan.linear()) < 1e-3);
  // a scan more than a second away is not this image's: nothing is moved
  frame.scan_timestamp = frame.timestamp - 1.5;
  CHECK(t.system.scan_motion(frame).matrix() == Eigen::Matrix4d::Identity());
}

// The threaded-mapping test lives in tests/reliability/test_threaded.cpp (label `threaded`, run under TSan).

TEST_CASE("a System without a depth source of its own tracks built frames, the same as one with it") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  BuiltSeq04 t(*dir);
  constexpr std::size_t kFrames = 12;
  for (std::size_t i = 0; i < kFrames; ++i) {
    const rgbl::SensorFrame frame = t.load(i);
    if (i == 0) CHECK_THROWS_AS(t.system.track(frame), std::logic_error);  // nothing to build it with
    CHECK(rgbl::has_pose(t.track(frame).state));
  }
  const auto own = rgbl::test::run_sequence(*dir, 0, kFrames);
  const rgbl::CameraCalibration& calibration = t.calibration;
  const auto built = t.system.trajectory();
  REQUIRE(built.size() == kFrames);
  for (std::size_t i = 0; i < kFrames; ++i) {
    const Eigen::Isometry3d T_world_cam0 = calibration.T_cam_cam0.inverse() * built[i].T_world_cam * calibration.T_cam_cam0;
    CHECK(T_world_cam0.matrix() == own.estimate[i].matrix());
  }
}

TEST_CASE("seq 04: each keyframe keeps the motion tracked from the one before, and local BA keeps to it") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  BuiltSeq04 t(*dir);
  for (std::size_t i = 0; i < 30; ++i) REQUIRE(rgbl::has_pose(t.track(t.load(i)).state));
  const rgbl::Map& map = t.system.map();
  int paired = 0;
  for (const rgbl::KeyframeId id : map.keyframe_ids()) {
    const rgbl::Keyframe& kf = *map.keyframe(id);
    if (!kf.previous.valid()) {
      CHECK(id.value == 0);  // only a map's first keyframe has none
      continue;
    }
    CHECK(kf.previous < id);
    const rgbl::Keyframe* previous = map.keyframe(kf.previous);
    REQUIRE(previous != nullptr);  // erasing a keyframe hands its successor the one before it
    // the map's relative pose against the tracked one (sigmas 0.1 m, 0.005 rad; the road decides
    // height and tilt)
    const Eigen::Isometry3d E = kf.T_cam_previous.inverse() * kf.T_cam_world * previous->T_cam_world.inverse();
    // 0.057 m at most, measured (keyframes at frames 19 and 22, which local BA takes 0.061 m from the
    // truth against the tracked 0.026 m; 0.022 m before keyframes came with reference_landmark_ratio)
    CHECK(E.translation().norm() < 0.08);
    CHECK(rgbl::so3_log(E.linear()).norm() < 0.005);  // 0.0012 rad at most, measured
    ++paired;
  }
  CHECK(paired >= 5);
}
