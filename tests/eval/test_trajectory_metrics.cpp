#include "rgbl/core/error.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/geometry/se3.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <vector>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

namespace {

using Poses = std::vector<Eigen::Isometry3d>;
constexpr double kDeg = 180.0 / std::numbers::pi;

// n poses 1 m apart along +z (cam0's forward), no rotation.
Poses straight_line(std::size_t n, double step = 1.0) {
  Poses poses;
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().z() = step * static_cast<double>(i);
    poses.push_back(T);
  }
  return poses;
}

// Each step moves 1 m forward and then yaws by `yaw` (about the camera's y axis).
Poses arc(std::size_t n, double yaw) {
  Poses poses{Eigen::Isometry3d::Identity()};
  const Eigen::Isometry3d step = rgbl::make_isometry(
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix(), Eigen::Vector3d(0, 0, 1));
  while (poses.size() < n) poses.push_back(poses.back() * step);
  return poses;
}

}  // namespace

TEST_CASE("KITTI metric: a 2 % scale error on a straight line", "[eval][kitti]") {
  const Poses gt = straight_line(1001);  // 1000 m
  const Poses est = straight_line(1001, 1.02);
  const auto m = rgbl::kitti_metric(est, gt);
  // The devkit's segment ends at the first frame whose distance EXCEEDS start + L: L + 1 m here, so
  // every segment of length L has t_err = 0.02 * (L + 1) / L. Starts every 10 frames while start + L + 1
  // <= 1000: 90 segments of 100 m ... 20 of 800 m.
  REQUIRE(m.per_length.size() == 8);
  double t_sum = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < 8; ++k) {
    const double L = 100.0 * static_cast<double>(k + 1);
    const auto& e = m.per_length[k];
    CHECK(e.length == L);
    CHECK(e.segments == static_cast<std::size_t>((999 - static_cast<int>(L)) / 10 + 1));
    CHECK_THAT(e.t_err_percent, WithinAbs(2.0 * (L + 1) / L, 1e-9));
    CHECK(e.r_err_deg_per_100m == 0.0);
    t_sum += e.segments * 2.0 * (L + 1) / L;
    n += e.segments;
  }
  CHECK(m.per_length[0].segments == 90);
  CHECK(m.per_length[7].segments == 20);
  CHECK(m.segments == n);
  CHECK(m.segment_errors.size() == n);
  CHECK_THAT(m.t_err_percent, WithinAbs(t_sum / static_cast<double>(n), 1e-9));
  CHECK(m.r_err_deg_per_100m == 0.0);

  const auto drift = rgbl::end_point_drift(est, gt);
  CHECK_THAT(drift.path_length, WithinAbs(1000.0, 1e-9));
  CHECK_THAT(drift.end_error, WithinAbs(20.0, 1e-9));
  CHECK_THAT(drift.percent, WithinAbs(2.0, 1e-9));

  const auto rpe = rgbl::relative_pose_error(est, gt);
  CHECK(rpe.translation_errors.size() == 1000);
  CHECK_THAT(rpe.translation.rmse, WithinAbs(0.02, 1e-12));
  CHECK_THAT(rpe.translation.max, WithinAbs(0.02, 1e-12));
  CHECK(rpe.rotation_deg.max == 0.0);
}

TEST_CASE("evaluation: the estimate's own path length beside the ground truth's", "[eval]") {
  // standing still while the car drives 10 m: the sign of a start locked on vehicles at the ego speed
  const Poses gt = straight_line(11);
  const Poses standing(11, Eigen::Isometry3d::Identity());
  const auto e = rgbl::evaluate_trajectory(standing, gt);
  CHECK_THAT(e.path_length, WithinAbs(10.0, 1e-12));
  CHECK_THAT(e.estimated_path_length, WithinAbs(0.0, 1e-12));
  const auto scaled = rgbl::evaluate_trajectory(straight_line(11, 1.02), gt);
  CHECK_THAT(scaled.estimated_path_length, WithinAbs(10.2, 1e-9));
}

TEST_CASE("KITTI metric: a constant yaw-rate error", "[eval][kitti]") {
  const double yaw = 1e-4;  // rad per metre
  const Poses gt = straight_line(301);
  const Poses est = arc(301, yaw);
  rgbl::KittiMetricOptions options;
  options.lengths = {50, 100};
  const auto m = rgbl::kitti_metric(est, gt, options);
  // A segment spans L + 1 steps: the heading error is (L + 1) * yaw, i.e. per metre (L + 1) / L * yaw.
  CHECK_THAT(m.per_length[0].r_err_deg_per_100m, WithinRel(51.0 / 50.0 * yaw * kDeg * 100.0, 1e-9));
  CHECK_THAT(m.per_length[1].r_err_deg_per_100m, WithinRel(101.0 / 100.0 * yaw * kDeg * 100.0, 1e-9));
  // Translation error: the arc's chord misses the straight segment end by ~ n^2 * yaw / 2.
  const double n = 101.0;
  CHECK_THAT(m.per_length[1].t_err_percent, WithinRel(100.0 * (n * (n - 1) / 2.0 * yaw) / 100.0, 1e-3));
  // RPE: every step's relative rotation is off by exactly `yaw`, its translation not at all.
  const auto rpe = rgbl::relative_pose_error(est, gt);
  CHECK_THAT(rpe.rotation_deg.mean, WithinRel(yaw * kDeg, 1e-6));
  CHECK_THAT(rpe.rotation_deg.median, WithinRel(yaw * kDeg, 1e-6));
  CHECK(rpe.translation.max < 1e-12);
}

TEST_CASE("metrics ignore the estimate's world frame, ATE aligns it away", "[eval][ate]") {
  const Poses gt = arc(200, 0.01);
  rgbl::Vector6d xi;
  xi << 3.0, -20.0, 7.0, 0.3, -1.1, 0.4;
  const Eigen::Isometry3d T_other_world = rgbl::se3_exp(xi);
  Poses est;
  for (const auto& T : gt) est.push_back(T_other_world * T);
  rgbl::KittiMetricOptions options;
  options.lengths = {20, 50, 100};
  const auto m = rgbl::kitti_metric(est, gt, options);
  CHECK(m.segments > 0);
  CHECK(m.t_err_percent < 1e-10);
  CHECK(m.r_err_deg_per_100m < 1e-4);  // the devkit's acos((trace - 1) / 2) resolves ~2e-8 rad only
  const auto ate = rgbl::absolute_trajectory_error(est, gt);
  CHECK(ate.translation.rmse < 1e-9);
  CHECK(ate.T_gt_est.isApprox(T_other_world.inverse(), 1e-9));
  const auto unaligned = rgbl::absolute_trajectory_error(est, gt, false);
  CHECK(unaligned.translation.rmse > 1.0);
  CHECK(rgbl::relative_pose_error(est, gt).translation.max < 1e-9);
  CHECK(rgbl::end_point_drift(est, gt).end_error < 1e-9);
}

TEST_CASE("ATE: hand-computed cases", "[eval][ate]") {
  // A square of radius sqrt(2) around (5, 0, 5); the estimate is 10 % larger. The best rigid fit
  // keeps the centre and orientation, leaving every point 0.1 * sqrt(2) off.
  Poses gt, est;
  for (const auto& c :
       {Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(-1, 0, 1), Eigen::Vector3d(-1, 0, -1), Eigen::Vector3d(1, 0, -1)}) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(5, 0, 5) + c;
    gt.push_back(T);
    T.translation() = Eigen::Vector3d(5, 0, 5) + 1.1 * c;
    est.push_back(T);
  }
  const auto ate = rgbl::absolute_trajectory_error(est, gt);
  CHECK_THAT(ate.translation.rmse, WithinAbs(0.1 * std::sqrt(2.0), 1e-12));
  CHECK_THAT(ate.translation.max, WithinAbs(0.1 * std::sqrt(2.0), 1e-12));
  CHECK(ate.T_gt_est.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  // A constant offset: aligned away, or its length when not aligned.
  Poses shifted = gt;
  for (auto& T : shifted) T.translation() += Eigen::Vector3d(3, 4, 0);
  CHECK(rgbl::absolute_trajectory_error(shifted, gt).translation.rmse < 1e-12);
  CHECK_THAT(rgbl::absolute_trajectory_error(shifted, gt, false).translation.rmse, WithinAbs(5.0, 1e-12));
  // errors 1, 2, 3, 4 m: rmse sqrt(7.5), mean 2.5, median 2.5
  const std::vector<double> errors{4, 1, 3, 2};
  const auto s = rgbl::error_stats(errors);
  CHECK_THAT(s.rmse, WithinAbs(std::sqrt(7.5), 1e-12));
  CHECK(s.mean == 2.5);
  CHECK(s.median == 2.5);
  CHECK(s.max == 4.0);
}

TEST_CASE("perturbed ground truth: errors grow with the perturbation", "[eval][kitti]") {
  const Poses gt = arc(400, 0.005);
  double previous = 0.0;
  for (double sigma : {0.01, 0.05, 0.2}) {
    // deterministic "noise": every pose shifted sideways by +-sigma
    Poses est = gt;
    for (std::size_t i = 0; i < est.size(); ++i) {
      est[i] =
          est[i] * rgbl::make_isometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(i % 2 == 0 ? sigma : -sigma, 0, 0));
    }
    rgbl::KittiMetricOptions options;
    options.lengths = {50, 100, 200};
    const auto m = rgbl::kitti_metric(est, gt, options);
    CHECK(m.t_err_percent > previous);
    // each segment's error is at most the two endpoints' offsets: 2 sigma / L
    for (const auto& s : m.segment_errors) CHECK(s.t_err <= 2.0 * sigma / s.length + 1e-12);
    previous = m.t_err_percent;
    const auto rpe = rgbl::relative_pose_error(est, gt);
    // neighbours are offset opposite ways, seen 0.005 rad apart: |x + R_y(0.005)^T x| sigma
    CHECK_THAT(rpe.translation.max, WithinAbs(2.0 * sigma * std::cos(0.0025), 1e-12));
    CHECK_THAT(rgbl::absolute_trajectory_error(est, gt, false).translation.rmse, WithinAbs(sigma, 1e-12));
  }
}

TEST_CASE("metrics: short runs, mismatched lengths and bad options", "[eval][bad-input]") {
  const Poses gt = straight_line(51);  // 50 m: no 100 m segment
  const auto m = rgbl::kitti_metric(gt, gt);
  CHECK(m.segments == 0);
  CHECK(std::isnan(m.t_err_percent));
  CHECK(std::isnan(m.per_length[0].t_err_percent));
  CHECK_THROWS_WITH(rgbl::kitti_metric(straight_line(50), gt), Contains("50 poses") && Contains("51"));
  CHECK_THROWS_AS(rgbl::absolute_trajectory_error(straight_line(3), gt), rgbl::Error);
  rgbl::KittiMetricOptions bad;
  bad.lengths = {10, -5};
  CHECK_THROWS_AS(rgbl::kitti_metric(gt, gt, bad), rgbl::ConfigError);
  bad.lengths = {10};
  bad.step_size = 0;
  CHECK_THROWS_AS(rgbl::kitti_metric(gt, gt, bad), rgbl::ConfigError);
  CHECK(std::isnan(rgbl::error_stats({}).rmse));
  CHECK(rgbl::trajectory_distances(gt).back() == 50.0);
}

TEST_CASE("KITTI metric: rotations that are orthonormal to 1e-7 only give no spurious rotation error",
          "[eval][kitti]") {
  // Like poses read from 7-digit files: equal rotations in estimate and truth, slightly off SO(3).
  Poses gt = arc(300, 0.003);
  for (auto& T : gt) T.linear() -= 3e-7 * Eigen::Matrix3d::Ones();  // trace < 3: acos sees it
  Poses est = gt;
  for (auto& T : est) T.translation() *= 1.01;
  rgbl::KittiMetricOptions options;
  options.lengths = {100};
  const auto m = rgbl::kitti_metric(est, gt, options);
  CHECK(m.segments > 0);
  CHECK(m.r_err_deg_per_100m < 1e-3);
  CHECK(rgbl::relative_pose_error(est, gt).rotation_deg.max < 1e-4);
}
