#include "bench/reference/scan_registration_reference.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/io/trajectory_io.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace {

// A LiDAR frame scene (x forward, y left, z up): the road, and optionally trunks every 7 m on both
// sides and a house front every 23 m on the left, sampled every 5 cm. Without them it is a corridor:
// road and two kerb walls, the same at every along-track shift.
std::vector<rgbl::LidarPoint> roadside(bool landmarks) {
  std::vector<rgbl::LidarPoint> points;
  const auto add = [&](double x, double y, double z) {
    points.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), 0.0F});
  };
  for (double x = -40.0; x <= 80.0; x += 0.2) {
    for (double y = -8.0; y <= 8.0; y += 0.2) add(x, y, -1.7);     // road
    for (double z = -1.7; z <= 0.3; z += 0.1) {                      // walls along it
      add(x, 8.0, z);
      add(x, -8.0, z);
    }
  }
  if (!landmarks) return points;
  for (double x = -35.0; x <= 80.0; x += 7.0) {  // trunks, 0.3 m across
    for (const double y : {-6.0, 6.0}) {
      for (double z = -1.7; z <= 3.0; z += 0.1) {
        for (double a = 0.0; a < 2.0 * std::numbers::pi; a += std::numbers::pi / 6.0) {
          add(x + 0.15 * std::cos(a), y + 0.15 * std::sin(a), z);
        }
      }
    }
  }
  for (double x0 = -30.0; x0 <= 80.0; x0 += 23.0) {  // house fronts facing the road, 10 m long
    for (double x = x0; x <= x0 + 10.0; x += 0.1) {
      for (double z = -1.7; z <= 5.0; z += 0.2) add(x, 12.0, z);
    }
    for (double y = 12.0; y <= 20.0; y += 0.1) {  // their side walls
      for (double z = -1.7; z <= 5.0; z += 0.2) {
        add(x0, y, z);
        add(x0 + 10.0, y, z);
      }
    }
  }
  return points;
}

// The scene's points in the frame of a sensor at T_scene_sensor.
std::vector<rgbl::LidarPoint> seen_from(const std::vector<rgbl::LidarPoint>& scene,
                                        const Eigen::Isometry3d& T_scene_sensor) {
  const Eigen::Isometry3f T = T_scene_sensor.inverse().cast<float>();
  std::vector<rgbl::LidarPoint> out;
  for (const rgbl::LidarPoint& p : scene) {
    const Eigen::Vector3f q = T * Eigen::Vector3f(p.x, p.y, p.z);
    out.push_back({q.x(), q.y(), q.z(), 0.0F});
  }
  return out;
}

double deg(const Eigen::Matrix3d& R) { return rgbl::rotation_angle(R) * 180.0 / std::numbers::pi; }

// The roadside at a bend: the query 22 m on and turned 17 deg, and the guess of a motion model that
// kept going straight into the bend (17 deg short, 2 m off).
struct Bend {
  Eigen::Isometry3d truth = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.0, 0.3}), {22.0, 3.0, 0.0});
  Eigen::Isometry3d guess = rgbl::make_isometry(Eigen::Matrix3d::Identity(), {22.5, 1.2, 0.0});
  std::vector<rgbl::LidarPoint> reference, query;
  Bend() {
    const auto scene = roadside(true);
    reference = seen_from(scene, Eigen::Isometry3d::Identity());
    query = seen_from(scene, truth);
  }
};

}  // namespace

TEST_CASE("scan registration: trunks and houses pin the pose down from a guess 1.5 m off") {
  const auto scene = roadside(true);
  const Eigen::Isometry3d truth = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.0, 0.05}), {25.0, 0.4, 0.0});
  const auto reference = seen_from(scene, Eigen::Isometry3d::Identity());
  const auto query = seen_from(scene, truth);
  const Eigen::Isometry3d guess = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.0, 0.02}), {26.2, -0.4, 0.3});
  const auto r = rgbl::register_scans(reference, query, guess);
  REQUIRE(r);
  const Eigen::Isometry3d error = truth.inverse() * r->T_reference_query;
  INFO(fmt::format("error {:.4f} m {:.4f} deg, {} iterations, agreement {:.3f}, probe loss {:.3f}",
                   error.translation().norm(), deg(error.linear()), r->iterations, r->agreement, r->min_probe_loss));
  CHECK(r->converged);
  CHECK(error.translation().norm() < 0.02);
  CHECK(deg(error.linear()) < 0.05);
  CHECK(r->agreement > 0.7);  // voxel means of two grids: about 0.8 on a flawless match
  CHECK(r->min_probe_loss > 0.1);
}

TEST_CASE("scan registration: a reference stored at its own voxel registers as the full scan does") {
  // voxel_downsample keeps one mean per voxel within the range: what register_scans keeps of a
  // reference, so the loop closer's stored scans give the result the full ones would
  const std::vector<rgbl::LidarPoint> few{{3.1F, 0.1F, 0.0F, 9.0F}, {3.3F, 0.3F, 0.2F, 9.0F},  // one voxel
                                          {4.6F, 0.0F, 0.0F, 1.0F},                           // another
                                          {1.0F, 0.0F, 0.0F, 1.0F}, {70.0F, 0.0F, 0.0F, 1.0F}};  // out of range
  const rgbl::ScanRegistrationOptions options;  // 3..60 m
  const auto kept = rgbl::voxel_downsample(few, options, 0.5);
  REQUIRE(kept.size() == 2);
  CHECK(kept[0].x == Approx(3.2F));
  CHECK(kept[0].y == Approx(0.2F));
  CHECK(kept[0].z == Approx(0.1F));
  CHECK(kept[0].intensity == 0.0F);
  CHECK(kept[1].x == Approx(4.6F));
  CHECK_THROWS_AS(rgbl::voxel_downsample(few, options, 0.0), rgbl::ConfigError);

  const auto scene = roadside(true);
  const Eigen::Isometry3d truth = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.0, 0.05}), {25.0, 0.4, 0.0});
  const auto reference = seen_from(scene, Eigen::Isometry3d::Identity());
  const auto query = seen_from(scene, truth);
  const Eigen::Isometry3d guess = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.0, 0.02}), {26.2, -0.4, 0.3});
  const auto stored = rgbl::voxel_downsample(reference, options, options.reference_voxel);
  CHECK(stored.size() < reference.size() / 5);
  const auto full = rgbl::register_scans(reference, query, guess);
  const auto from_stored = rgbl::register_scans(stored, query, guess);
  REQUIRE(full);
  REQUIRE(from_stored);
  const Eigen::Isometry3d difference = full->T_reference_query.inverse() * from_stored->T_reference_query;
  CHECK(difference.translation().norm() < 1e-4);
  CHECK(deg(difference.linear()) < 1e-3);
}

TEST_CASE("scan registration: a corridor leaves the along-track position open, and the probe says so") {
  const auto scene = roadside(false);
  const Eigen::Isometry3d truth = rgbl::make_isometry(Eigen::Matrix3d::Identity(), {25.0, 0.0, 0.0});
  const auto reference = seen_from(scene, Eigen::Isometry3d::Identity());
  const auto query = seen_from(scene, truth);
  const Eigen::Isometry3d guess = rgbl::make_isometry(Eigen::Matrix3d::Identity(), {26.0, 0.3, 0.0});
  const auto r = rgbl::register_scans(reference, query, guess);
  REQUIRE(r);
  INFO(fmt::format("probe loss {:.3f}, agreement {:.3f}", r->min_probe_loss, r->agreement));
  // across the road and vertically it is pinned down, along it any shift fits as well
  CHECK(std::abs(r->T_reference_query.translation().y()) < 0.05);
  CHECK(r->agreement > 0.7);  // voxel means of two grids: about 0.8 on a flawless match
  CHECK(r->min_probe_loss < 0.02);
}

TEST_CASE("scan registration: a guess turned 15 deg too far is found again by the heading search") {
  const Bend bend;
  const Eigen::Isometry3d &truth = bend.truth, &guess = bend.guess;
  const std::vector<rgbl::LidarPoint> &reference = bend.reference, &query = bend.query;
  rgbl::ScanRegistrationOptions o;
  const auto single = rgbl::register_scans(reference, query, guess, o);
  const auto error_of = [&](const rgbl::ScanRegistration& r) { return truth.inverse() * r.T_reference_query; };
  // from the guess alone ICP does not reach it
  CHECK((!single || !single->converged || error_of(*single).translation().norm() > 0.5));
  o.yaw_range_deg = 25.0;
  const auto r = rgbl::register_scans(reference, query, guess, o);
  REQUIRE(r);
  const Eigen::Isometry3d error = error_of(*r);
  INFO(fmt::format("error {:.4f} m {:.4f} deg, {} of {} starts converged, agreement {:.3f}, runner-up {:.3f}, probe "
                   "loss {:.3f}",
                   error.translation().norm(), deg(error.linear()), r->converged_starts, r->starts, r->agreement,
                   r->runner_up_agreement, r->min_probe_loss));
  CHECK(r->starts == 11);  // 0, +-5, ..., +-25 deg
  CHECK(r->converged);
  CHECK(error.translation().norm() < 0.02);
  CHECK(deg(error.linear()) < 0.05);
  CHECK(r->runner_up_agreement < 0.8 * r->agreement);
  CHECK(r->min_probe_loss > 0.1);
}

TEST_CASE("registration across a gap: searched and accepted within what the gap allows, refused beyond or on a ridge") {
  const Bend bend;
  const Eigen::Isometry3d &truth = bend.truth, &guess = bend.guess;
  const std::vector<rgbl::LidarPoint> &reference = bend.reference, &query = bend.query;
  const rgbl::GapRegistrationOptions o;
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();  // the scans' frames are the "camera" frames
  // 1 s: 2 + 25 deg and 1 + 2 m allowed; the 17 deg and 1.9 m the guess is off are within, and searched
  const auto g = rgbl::register_across_gap(reference, query, I, guess, 1.0, o);
  REQUIRE(g);
  const Eigen::Isometry3d error = truth.inverse() * g->registration.T_reference_query;
  INFO(fmt::format("error {:.4f} m, moved {:.2f} m {:.2f} deg of {:.2f} m {:.2f} deg", error.translation().norm(),
                   g->moved_m, g->moved_deg, g->allowed_m, g->allowed_deg));
  CHECK(g->allowed_m == Approx(3.0));
  CHECK(g->allowed_deg == Approx(27.0));
  CHECK(g->accepted);
  CHECK(error.translation().norm() < 0.02);
  CHECK(g->moved_deg == Approx(17.19).margin(0.05));
  CHECK(g->moved_m == Approx((truth.translation() - guess.translation()).norm()).margin(0.02));
  // Extrinsics printed to 7 digits (KITTI's) are a rotation to ~1e-7 only; the camera motion that
  // comes out is one to rounding, or a tracker chaining such motions frame after frame drifts off.
  Eigen::Isometry3d T_cam_lidar = rgbl::make_isometry(rgbl::so3_exp({1.2, -1.2, 1.2}), {0.27, -0.08, -0.06});
  T_cam_lidar.linear() = (T_cam_lidar.linear() * 1e7).array().round() / 1e7;
  REQUIRE(rgbl::rotation_error(T_cam_lidar.linear()) > 1e-9);
  const auto printed = rgbl::register_across_gap(reference, query, T_cam_lidar,
                                                 T_cam_lidar * guess * T_cam_lidar.inverse(), 1.0, o);
  REQUIRE(printed);
  CHECK(rgbl::rotation_error(printed->T_reference_query.linear()) < 1e-12);
  CHECK(printed->accepted);
  // 0.2 s: the guess cannot be 17 deg off (7 deg allowed), so whatever the search finds is not taken
  const auto tight = rgbl::register_across_gap(reference, query, I, guess, 0.2, o);
  CHECK((!tight || !tight->accepted));
  // a road between two rows of rails: the result slides along it, the probe refuses it
  const auto corridor = roadside(false);
  const auto slide = rgbl::register_across_gap(
      seen_from(corridor, Eigen::Isometry3d::Identity()),
      seen_from(corridor, rgbl::make_isometry(Eigen::Matrix3d::Identity(), {25.0, 0.0, 0.0})), I,
      rgbl::make_isometry(Eigen::Matrix3d::Identity(), {26.0, 0.3, 0.0}), 1.0, o);
  REQUIRE(slide);
  CHECK_FALSE(slide->accepted);
  rgbl::GapRegistrationOptions bad;
  bad.max_runner_up_ratio = 0.0;
  CHECK_THROWS_AS(rgbl::register_across_gap(reference, query, I, guess, 1.0, bad), rgbl::ConfigError);
}

TEST_CASE("registration across a gap: the same result on a task pool as inline") {
  const Bend bend;
  const Eigen::Isometry3d& guess = bend.guess;
  const std::vector<rgbl::LidarPoint> &reference = bend.reference, &query = bend.query;
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  const auto inline_run = rgbl::register_across_gap(reference, query, I, guess, 1.0, {});
  REQUIRE(inline_run);
  REQUIRE(inline_run->registration.starts > 1);  // a search, so there is something to split
  for (const int threads : {1, 2, 3}) {
    rgbl::TaskPool pool(threads);
    const auto pooled = rgbl::register_across_gap(reference, query, I, guess, 1.0, {}, &pool);
    REQUIRE(pooled);
    INFO(threads << " threads");
    // bit for bit: each start is computed alone and gathered in order
    CHECK(pooled->T_reference_query.matrix() == inline_run->T_reference_query.matrix());
    CHECK(pooled->registration.converged_starts == inline_run->registration.converged_starts);
    CHECK(pooled->registration.iterations == inline_run->registration.iterations);
    CHECK(pooled->registration.agreement == inline_run->registration.agreement);
    CHECK(pooled->registration.runner_up_agreement == inline_run->registration.runner_up_agreement);
    CHECK(pooled->registration.min_probe_loss == inline_run->registration.min_probe_loss);
    CHECK(pooled->accepted == inline_run->accepted);
  }
}

TEST_CASE("scan registration: too little to register is no result, bad options are errors") {
  std::vector<rgbl::LidarPoint> few{{5.0F, 0.0F, 0.0F, 0.0F}, {6.0F, 0.0F, 0.0F, 0.0F}};
  CHECK_FALSE(rgbl::register_scans(few, few, Eigen::Isometry3d::Identity()));
  rgbl::ScanRegistrationOptions o;
  o.fine_distance = 2.0 * o.coarse_distance;
  CHECK_THROWS_AS(o.validate(), rgbl::ConfigError);
  o = {};
  o.yaw_range_deg = 190.0;
  CHECK_THROWS_AS(o.validate(), rgbl::ConfigError);
  o = {};
  o.probe_shift_m = 0.0;
  CHECK_THROWS_AS(rgbl::register_scans(few, few, Eigen::Isometry3d::Identity(), o), rgbl::ConfigError);
}

// Sequence 04's scans 32 m apart (frames 13 and 36, 2.3 s; the reliability test's jump bridges
// frames 12 and 36):
// from the constant-velocity guess over the gap, the registration lands on the truth and is a peak;
// from a guess 35 m short (the same jump without the clock's gap), it slides along the road.
TEST_CASE("scan registration on sequence 04: 32 m apart from the motion model's guess") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  const rgbl::KittiCalibration calibration = rgbl::read_kitti_odometry_calibration(*sequence / "calib.txt");
  const auto poses = rgbl::read_kitti_trajectory(*sequence / "../../poses/04.txt");  // T_world_cam0
  const Eigen::Isometry3d T_cam_lidar = calibration.T_cam0_lidar;
  const auto scan = [&](int i) { return rgbl::read_kitti_scan(*sequence / "velodyne" / fmt::format("{:06d}.bin", i)); };
  // T_lidarA_lidarB from camera poses
  const auto lidar_motion = [&](const Eigen::Isometry3d& T_camA_camB) {
    return T_cam_lidar.inverse() * T_camA_camB * T_cam_lidar;
  };
  const Eigen::Isometry3d step = poses[12].inverse() * poses[13];  // the motion model's velocity
  const auto extrapolate = [&](int steps) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int i = 0; i < steps; ++i) T = T * step;
    return T;
  };
  const auto reference = scan(13);
  {
    const auto query = scan(36);
    const Eigen::Isometry3d truth = lidar_motion(poses[13].inverse() * poses[36]);
    const Eigen::Isometry3d guess = lidar_motion(extrapolate(23));
    const auto r = rgbl::register_scans(reference, query, guess);
    REQUIRE(r);
    const Eigen::Isometry3d guess_error = truth.inverse() * guess;
    const Eigen::Isometry3d error = truth.inverse() * r->T_reference_query;
    INFO(fmt::format("guess {:.3f} m off; result {:.3f} m {:.3f} deg off, {} iterations, agreement {:.3f}, probe "
                     "loss {:.3f}",
                     guess_error.translation().norm(), error.translation().norm(), deg(error.linear()), r->iterations,
                     r->agreement, r->min_probe_loss));
    CHECK(guess_error.translation().norm() > 1.0);
    CHECK(r->converged);
    CHECK(error.translation().norm() < 0.25);
    CHECK(deg(error.linear()) < 0.4);
    CHECK(r->min_probe_loss > 0.15);
  }
  {
    const auto query = scan(40);
    const Eigen::Isometry3d guess = lidar_motion(extrapolate(1));  // 35 m short
    const auto r = rgbl::register_scans(reference, query, guess);
    if (r) {
      INFO(fmt::format("probe loss {:.3f}, agreement {:.3f}", r->min_probe_loss, r->agreement));
      WARN(fmt::format("35 m short: probe loss {:.3f}, agreement {:.3f}", r->min_probe_loss, r->agreement));
      CHECK(r->min_probe_loss < 0.05);
    }
  }
}

TEST_CASE("scan registration: the same result as the straightforward implementation") {
  // rgbl keeps each query point's neighbourhood while the point stays inside it and fits the planes
  // pair by pair; bench/reference searches every voxel around every point in every iteration.
  const auto compare = [](const std::vector<rgbl::LidarPoint>& reference, const std::vector<rgbl::LidarPoint>& query,
                          const Eigen::Isometry3d& guess, const rgbl::ScanRegistrationOptions& options) {
    const auto r = rgbl::register_scans(reference, query, guess, options);
    const auto straight = rgbl::reference::register_scans(reference, query, guess, options);
    REQUIRE(r);
    REQUIRE(straight);
    const Eigen::Isometry3d difference = straight->T_reference_query.inverse() * r->T_reference_query;
    INFO(fmt::format("{:.2e} m, {:.2e} deg apart; iterations {} and {}; agreement {:.5f} and {:.5f}; probe loss {:.5f} and {:.5f}",
                     difference.translation().norm(), deg(difference.linear()), r->iterations, straight->iterations,
                     r->agreement, straight->agreement, r->min_probe_loss, straight->min_probe_loss));
    CHECK(r->converged == straight->converged);
    CHECK(r->iterations == straight->iterations);
    CHECK(difference.translation().norm() < 1e-5);
    CHECK(deg(difference.linear()) < 1e-4);
    CHECK(r->agreement == Approx(straight->agreement).margin(1e-3));
    CHECK(r->min_probe_loss == Approx(straight->min_probe_loss).margin(1e-3));
  };
  SECTION("trunks and houses, 1.5 m off, the default options") {
    // jittered by up to 1 cm: on the exact grid, equidistant neighbours are ties that float and double
    // break differently (1 mm apart at the end, the same with the grid searched every time)
    auto scene = roadside(true);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> jitter(-0.01F, 0.01F);
    for (rgbl::LidarPoint& p : scene) {
      p.x += jitter(rng);
      p.y += jitter(rng);
      p.z += jitter(rng);
    }
    Eigen::Isometry3d T_scene_query = Eigen::Isometry3d::Identity();
    T_scene_query.translation() = Eigen::Vector3d(3.0, 0.2, 0.0);
    Eigen::Isometry3d guess = T_scene_query;
    guess.translation().x() += 1.5;
    compare(seen_from(scene, Eigen::Isometry3d::Identity()), seen_from(scene, T_scene_query), guess, {});
  }
  SECTION("sequence 04's keyframes 3 frames apart, the keyframe pairs' options") {
    const auto sequence = rgbl::test::kitti_seq04();
    if (!sequence) return;
    const rgbl::KittiCalibration calibration = rgbl::read_kitti_odometry_calibration(*sequence / "calib.txt");
    const auto sample = [&](int i) {
      return rgbl::as_points(rgbl::sample_scan(rgbl::read_kitti_scan(*sequence / "velodyne" / fmt::format("{:06d}.bin", i)),
                                               calibration.T_cam0_lidar, rgbl::ScanSampleOptions{}));
    };
    // LocalMappingOptions::lidar_registration (tracking is above geometry: its values, restated)
    const rgbl::ScanRegistrationOptions pairs{.min_range = 2.0, .max_range = 40.0, .reference_voxel = 0.3,
                                              .query_voxel = 0.3, .coarse_distance = 0.5, .coarse_iterations = 3,
                                              .fine_distance = 0.3, .robust_scale = 0.1};
    Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
    guess.translation() = Eigen::Vector3d(0.0, 0.0, 4.0);  // camera frame: 4 m ahead
    for (const auto& [a, b] : {std::pair{0, 3}, std::pair{10, 14}, std::pair{30, 33}}) {
      INFO(fmt::format("frames {} and {}", a, b));
      compare(sample(a), sample(b), guess, pairs);
    }
  }
}
