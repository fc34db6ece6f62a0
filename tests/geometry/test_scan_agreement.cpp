#include "rgbl/core/error.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/se3.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
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

TEST_CASE("scan objects: touching voxels share a label, labels in order of first appearance") {
  rgbl::ScanSample s;
  s.points = {{0.05F, 0.05F, 10.05F},  // object 0
              {5.05F, 0.05F, 10.05F},  // object 1: 5 m to the right
              {0.35F, 0.35F, 10.35F},  // object 0: the next voxel diagonally (corners touch)
              {0.95F, 0.05F, 10.05F},  // a voxel between it and object 0 is empty: object 2
              {0.65F, 0.05F, 10.05F},  // ... until this return fills it: object 0 again, so is the one before
              {5.10F, 0.10F, 10.10F}};  // object 1, same voxel
  const std::vector<std::uint32_t> labels = rgbl::label_objects(s, 0.3);
  CHECK(labels == std::vector<std::uint32_t>{0, 1, 0, 0, 0, 1});
  CHECK(rgbl::label_objects(rgbl::ScanSample{}, 0.3).empty());
  CHECK_THROWS_AS(rgbl::label_objects(s, 0.0), rgbl::ConfigError);
}

TEST_CASE("signed-rank z: Wilcoxon's statistic, exact on small sets") {
  using V = std::vector<double>;
  // 1..5 all positive: W+ = 15 against a mean of 7.5 and a variance of 5 * 6 * 11 / 24 = 13.75
  CHECK(rgbl::signed_rank_z(V{1, 2, 3, 4, 5}) == Approx(7.5 / std::sqrt(13.75)));
  CHECK(rgbl::signed_rank_z(V{-1, -2, -3, -4, -5}) == Approx(-7.5 / std::sqrt(13.75)));
  // ties share their average rank (2 each), and the variance loses (3^3 - 3) / 48:
  // W+ = 4 against 3, variance 3 * 4 * 7 / 24 - 0.5 = 3
  CHECK(rgbl::signed_rank_z(V{1, -1, 1}) == Approx(1.0 / std::sqrt(3.0)));
  // zeros are dropped; nothing left is no evidence
  CHECK(rgbl::signed_rank_z(V{0, 1, 0, -1}) == Approx(0.0));
  CHECK(rgbl::signed_rank_z(V{0, 0}) == 0.0);
  CHECK(rgbl::signed_rank_z(V{}) == 0.0);
  // one large difference against many small ones of the other sign: the many win on ranks
  V many(18, -3.0);
  many.push_back(400.0);
  CHECK(rgbl::signed_rank_z(many) < -3.0);
}

TEST_CASE("scan vote by object: a truck keeping pace, many returns on one face, does not outvote the street") {
  // 18 thin poles, sparsely sampled, and the rear of a truck in the next lane that keeps pace with
  // the camera (the same camera coordinates before and after the step), densely sampled.
  rgbl::ScanSample poles;
  for (double z = 4.0; z <= 36.0; z += 4.0) {
    for (const double x : {-5.0, 5.0}) {
      for (double y = -2.0; y <= 1.5; y += 0.25) {
        for (double a = 0.0; a < 2.0 * M_PI; a += M_PI / 2.0) {
          poles.points.emplace_back(static_cast<float>(x + 0.15 * std::cos(a)), static_cast<float>(y),
                                    static_cast<float>(z + 0.15 * std::sin(a)));
        }
      }
    }
  }
  rgbl::ScanSample truck;  // 0.85 m clear of the right poles, so that no voxel of the one touches the other
  for (double x = 2.0; x <= 4.0; x += 0.05) {
    for (double y = -2.5; y <= 1.0; y += 0.05) truck.points.emplace_back(static_cast<float>(x), static_cast<float>(y), 10.0F);
  }
  const Eigen::Isometry3d truth(Eigen::Translation3d(0.0, 0.0, 2.0));
  const Eigen::Isometry3d still = Eigen::Isometry3d::Identity();
  rgbl::ScanSample before = poles, after = seen_from(poles, truth);
  before.points.insert(before.points.end(), truck.points.begin(), truck.points.end());
  after.points.insert(after.points.end(), truck.points.begin(), truck.points.end());
  REQUIRE(truck.points.size() > 2 * poles.points.size());
  const rgbl::ScanAgreement agreement(before, 0.3);
  const std::vector<std::uint32_t> objects = rgbl::label_objects(after, 0.3);
  REQUIRE(*std::max_element(objects.begin(), objects.end()) == 18);  // 18 poles and the truck

  // per return: the truck's face outvotes the poles
  const rgbl::ScanVote vote = agreement.vote(after, truth, still, objects);
  CHECK(vote.only_a == poles.points.size());
  CHECK(vote.only_b == truck.points.size());
  CHECK(vote.preference() == 1);
  // per object: 18 poles against one face. W+ = 19 (the face has the top rank), mean 95, variance
  // 19 * 20 * 39 / 24 - (18^3 - 18) / 48
  const double variance = 19.0 * 20.0 * 39.0 / 24.0 - (18.0 * 18.0 * 18.0 - 18.0) / 48.0;
  CHECK(vote.object_z == Approx((19.0 - 95.0) / std::sqrt(variance)));
  CHECK(vote.object_preference() == -1);
  CHECK(agreement.vote(after, still, truth, objects).object_preference() == 1);
  CHECK(agreement.vote(after, truth, truth, objects).object_preference() == 0);  // nothing discordant
  // without objects the vote has no z and object_preference() is preference()
  CHECK(std::isnan(agreement.vote(after, truth, still).object_z));
  CHECK(agreement.vote(after, truth, still).object_preference() == 1);
  // a label per point or none
  CHECK_THROWS_AS(agreement.vote(after, truth, still, std::span(objects).first(3)), rgbl::ConfigError);

  // without the poles' help (four of them left), the face alone against them decides nothing
  rgbl::ScanSample few_before, few_after;
  for (std::size_t i = 0; i < before.points.size(); ++i) {
    const bool far_pole = i < poles.points.size() && before.points[i].z() > 9.0F;
    if (far_pole) continue;
    few_before.points.push_back(before.points[i]);
    few_after.points.push_back(after.points[i]);
  }
  const rgbl::ScanAgreement few(few_before, 0.3);
  const rgbl::ScanVote undecided = few.vote(few_after, truth, still, rgbl::label_objects(few_after, 0.3));
  INFO("z " << undecided.object_z);
  CHECK(undecided.preference() == 1);
  CHECK(undecided.object_preference() == 0);
}

TEST_CASE("scan vote: McNemar's bound at 3 sigma decides, nothing below it") {
  CHECK(rgbl::ScanVote{0, 0}.preference() == 0);
  CHECK(rgbl::ScanVote{0, 9}.preference() == 0);   // 9 <= 3 * 3
  CHECK(rgbl::ScanVote{0, 10}.preference() == 1);  // 10 > 3 * sqrt(10)
  CHECK(rgbl::ScanVote{100, 130}.preference() == 0);  // 30 <= 45.5
  CHECK(rgbl::ScanVote{100, 150}.preference() == 1);  // 50 > 47.4
  CHECK(rgbl::ScanVote{150, 100}.preference() == -1);
}

TEST_CASE("scan sample: an elevation correction turns each return up about p x z, its range and azimuth kept") {
  // returns in four directions, on and off the horizon; the identity keeps the LiDAR frame
  const std::vector<rgbl::LidarPoint> scan = {
      {10.0F, 0.0F, -1.73F, 0.0F}, {0.0F, -20.0F, 0.0F, 0.0F}, {-6.0F, 8.0F, 2.0F, 0.0F}, {3.0F, 4.0F, -12.0F, 0.0F}};
  rgbl::ScanSampleOptions options;
  options.stride = 1;
  options.elevation_correction_deg = 0.205;
  const rgbl::ScanSample turned = rgbl::sample_scan(scan, Eigen::Isometry3d::Identity(), options);
  REQUIRE(turned.points.size() == scan.size());
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Eigen::Vector3d p(scan[i].x, scan[i].y, scan[i].z), q = turned.points[i].cast<double>();
    CHECK_THAT(q.norm(), Catch::Matchers::WithinRel(p.norm(), 1e-6));
    CHECK_THAT(std::atan2(q.y(), q.x()), Catch::Matchers::WithinAbs(std::atan2(p.y(), p.x()), 1e-6));
    const double elevation = std::asin(p.z() / p.norm()), turned_elevation = std::asin(q.z() / q.norm());
    CHECK_THAT(turned_elevation - elevation, Catch::Matchers::WithinAbs(0.205 * kDeg, 1e-6));
  }
  // the road 10 m ahead of a LiDAR 1.73 m up comes 0.036 m up and 0.006 m nearer
  const double a = 0.205 * kDeg;
  CHECK_THAT(turned.points[0].z(), Catch::Matchers::WithinAbs(10.0 * std::sin(a) - 1.73 * std::cos(a), 1e-5));
  CHECK_THAT(turned.points[0].x(), Catch::Matchers::WithinAbs(10.0 * std::cos(a) + 1.73 * std::sin(a), 1e-5));
  options.elevation_correction_deg = 2.5;
  CHECK_THROWS_AS(options.validate(), rgbl::ConfigError);
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
