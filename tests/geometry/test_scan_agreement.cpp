#include "rgbl/core/error.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/se3.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace {

// Poles every 4 m on both sides of a street and a wall at its end, sampled every 5 cm: what a scan
// sees that moves under a step along the street (the poles' fronts, the wall). Camera frame: x right,
// y down, z forward.
rgbl::ScanSample street() {
  rgbl::ScanSample s;
  for (double z = 4.0; z <= 36.0; z += 4.0) {
    for (const double x : {-5.0, 5.0}) {
      for (double y = -2.0; y <= 1.5; y += 0.05) {
        for (double a = 0.0; a < 2.0 * M_PI; a += M_PI / 8.0) {
          s.points.emplace_back(static_cast<float>(x + 0.15 * std::cos(a)), static_cast<float>(y),
                                static_cast<float>(z + 0.15 * std::sin(a)));
        }
      }
    }
  }
  for (double x = -6.0; x <= 6.0; x += 0.05) {
    for (double y = -3.0; y <= 1.5; y += 0.25) s.points.emplace_back(static_cast<float>(x), static_cast<float>(y), 38.0F);
  }
  return s;
}

// The sample as seen from a camera moved by T_before_after (points in the new camera frame).
rgbl::ScanSample seen_from(const rgbl::ScanSample& scene, const Eigen::Isometry3d& T_before_after) {
  rgbl::ScanSample s;
  const Eigen::Isometry3f T = T_before_after.inverse().cast<float>();
  for (const Eigen::Vector3f& p : scene.points) s.points.push_back(T * p);
  return s;
}

}  // namespace

TEST_CASE("scan agreement: every point lands on its scene under the true motion, few under a wrong one") {
  const rgbl::ScanSample before = street();
  const Eigen::Isometry3d truth = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.02, 0.0}), {0.1, 0.0, 2.0});
  const rgbl::ScanSample after = seen_from(before, truth);
  const rgbl::ScanAgreement agreement(before, 0.3);
  CHECK(agreement.count(after, truth) == after.points.size());
  // standing still: the poles' and the wall's returns sit 2 m off theirs
  const Eigen::Isometry3d still = Eigen::Isometry3d::Identity();
  const std::size_t still_count = agreement.count(after, still);
  CHECK(still_count < after.points.size() / 10);
  const std::vector<bool> flags = agreement.agreeing(after, still);
  CHECK(static_cast<std::size_t>(std::count(flags.begin(), flags.end(), true)) == still_count);

  // the vote: the points that agree under one pose only, and McNemar's test on them
  const rgbl::ScanVote vote = agreement.vote(after, still, truth);
  CHECK(vote.only_a == 0);  // everything lands under the truth
  CHECK(vote.only_b == after.points.size() - still_count);
  CHECK(vote.preference() == 1);
  CHECK(agreement.vote(after, truth, still).preference() == -1);
  CHECK(agreement.vote(after, truth, truth).preference() == 0);  // nothing discordant
  // a shift within the tolerance is no evidence either way
  const Eigen::Isometry3d near = truth * Eigen::Translation3d(0.0, 0.0, 0.1);
  CHECK(agreement.vote(after, truth, near).preference() == 0);
  // a pose gone wild lands nothing (and converts no huge or NaN coordinate to a voxel)
  CHECK(agreement.count(after, Eigen::Isometry3d(Eigen::Translation3d(1e12, 0.0, 0.0))) == 0);
  Eigen::Isometry3d nan = truth;
  nan.translation().x() = std::numeric_limits<double>::quiet_NaN();
  CHECK(agreement.count(after, nan) == 0);
}

TEST_CASE("scan vote: McNemar's bound at 3 sigma decides, nothing below it") {
  CHECK(rgbl::ScanVote{0, 0}.preference() == 0);
  CHECK(rgbl::ScanVote{0, 9}.preference() == 0);   // 9 <= 3 * 3
  CHECK(rgbl::ScanVote{0, 10}.preference() == 1);  // 10 > 3 * sqrt(10)
  CHECK(rgbl::ScanVote{100, 130}.preference() == 0);  // 30 <= 45.5
  CHECK(rgbl::ScanVote{100, 150}.preference() == 1);  // 50 > 47.4
  CHECK(rgbl::ScanVote{150, 100}.preference() == -1);
}

TEST_CASE("scan sample: every stride-th return within the range band, in the camera frame") {
  std::vector<rgbl::LidarPoint> scan;
  for (int i = 0; i < 100; ++i) scan.push_back({static_cast<float>(i), 0.0F, 0.0F, 0.0F});  // x ahead, 0..99 m
  scan[10].x = std::numeric_limits<float>::quiet_NaN();
  // LiDAR x forward, y left, z up -> camera x right, y down, z forward, 1 m behind the camera
  Eigen::Isometry3d T_cam_lidar = Eigen::Isometry3d::Identity();
  T_cam_lidar.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  T_cam_lidar.translation() = Eigen::Vector3d(0.0, 0.0, -1.0);
  rgbl::ScanSampleOptions options;
  options.stride = 5;
  options.min_range = 2.0;
  options.max_range = 40.0;
  const rgbl::ScanSample sample = rgbl::sample_scan(scan, T_cam_lidar, options);
  // i = 0, 5, ..., 95: 0 is too near, 10 is NaN, 45 and beyond too far -> 5, 15, 20, ..., 40
  REQUIRE(sample.points.size() == 7);
  CHECK(sample.points.front().isApprox(Eigen::Vector3f(0.0F, 0.0F, 4.0F)));
  CHECK(sample.points.back().isApprox(Eigen::Vector3f(0.0F, 0.0F, 39.0F)));
  CHECK(rgbl::sample_scan({}, T_cam_lidar, options).empty());

  options.stride = 0;
  CHECK_THROWS_AS(options.validate(), rgbl::ConfigError);
  options.stride = 1;
  options.tolerance = 0.0;
  CHECK_THROWS_AS(options.validate(), rgbl::ConfigError);
}
