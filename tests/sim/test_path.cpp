#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/sim/path.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {
constexpr double kPi = std::numbers::pi;
}

TEST_CASE("path kinds parse and print") {
  for (const auto kind : {rgbl::PathKind::straight, rgbl::PathKind::curve, rgbl::PathKind::loop}) {
    CHECK(rgbl::parse_path_kind(rgbl::to_string(kind)) == kind);
  }
  CHECK_FALSE(rgbl::parse_path_kind("zigzag").has_value());
}

TEST_CASE("straight path: level camera moving along +z, first pose identity") {
  rgbl::PathOptions options;
  const rgbl::DrivePath path(options, 50.0);
  CHECK(path.pose(0.0).matrix() == Eigen::Matrix4d::Identity());
  const Eigen::Isometry3d T = path.pose(17.5);
  CHECK((T.translation() - Eigen::Vector3d(0.0, 0.0, 17.5)).norm() < 1e-12);
  CHECK(rgbl::rotation_angle(T.linear()) < 1e-12);
  // open paths continue straight before the start (for laying out the scene behind the car)
  CHECK((path.pose(-10.0).translation() - Eigen::Vector3d(0.0, 0.0, -10.0)).norm() < 1e-12);
}

TEST_CASE("arc geometry: a left bend turns towards -x by length / radius") {
  // 10 m straight, then a quarter circle of radius 20 m to the left
  const rgbl::DrivePath path({{10.0, 0.0}, {20.0 * kPi / 2.0, 1.0 / 20.0}}, false);
  const rgbl::PathPoint end = path.at(10.0 + 20.0 * kPi / 2.0);
  CHECK_THAT(end.x, WithinAbs(-20.0, 1e-9));
  CHECK_THAT(end.z, WithinAbs(30.0, 1e-9));
  CHECK_THAT(end.heading, WithinAbs(-kPi / 2.0, 1e-12));
  // the camera now looks along -x: its optical axis (third column of R) is (-1, 0, 0)
  const Eigen::Isometry3d T = path.pose(10.0 + 20.0 * kPi / 2.0);
  CHECK((T.linear().col(2) - Eigen::Vector3d(-1.0, 0.0, 0.0)).norm() < 1e-12);
  // a point on the circle halfway: centre (-20, 10), radius 20
  const rgbl::PathPoint mid = path.at(10.0 + 20.0 * kPi / 4.0);
  CHECK_THAT(std::hypot(mid.x + 20.0, mid.z - 10.0), WithinAbs(20.0, 1e-9));
  // lateral offsets: 2 m to the right of the start is (2, 0)
  CHECK((path.point(0.0, 2.0) - Eigen::Vector2d(2.0, 0.0)).norm() < 1e-12);
}

TEST_CASE("curve path alternates left and right bends of the chosen angle") {
  rgbl::PathOptions options;
  options.kind = rgbl::PathKind::curve;
  const rgbl::DrivePath path(options, 300.0);
  const double arc = options.bend_radius * options.bend_angle_deg * kPi / 180.0;
  const double after_first = options.bend_straight + arc;
  CHECK_THAT(path.at(after_first).heading, WithinAbs(-options.bend_angle_deg * kPi / 180.0, 1e-12));
  CHECK_THAT(path.at(2.0 * after_first).heading, WithinAbs(0.0, 1e-12));
  // constant speed: consecutive 1 m steps are 1 m apart (chords of arcs: a hair less)
  for (double s = 0.0; s < 300.0; s += 1.0) {
    const double d = (path.pose(s + 1.0).translation() - path.pose(s).translation()).norm();
    REQUIRE(d <= 1.0 + 1e-12);
    REQUIRE(d > 0.9998);
  }
}

TEST_CASE("loop returns exactly to the start") {
  rgbl::SyntheticOptions options;
  options.frames = 120;
  options.path.kind = rgbl::PathKind::loop;
  const rgbl::SyntheticGenerator generator(options);
  const Eigen::Isometry3d first = generator.pose(0);
  const Eigen::Isometry3d last = generator.pose(options.frames - 1);
  CHECK(first.matrix() == Eigen::Matrix4d::Identity());
  CHECK((last.translation() - first.translation()).norm() < 1e-9);
  CHECK(rgbl::rotation_angle(last.linear() * first.linear().transpose()) < 1e-9);
  // ... and it really went round: the frame before last is 1 m behind, the middle far away, and the
  // pose just before the end approaches the start continuously
  CHECK_THAT((generator.pose(options.frames - 2).translation() - first.translation()).norm(), WithinAbs(1.0, 1e-9));
  double farthest = 0.0;
  for (int i = 0; i < options.frames; ++i) farthest = std::max(farthest, generator.pose(i).translation().norm());
  CHECK(farthest > 30.0);
  const rgbl::DrivePath& path = generator.path();
  const double L = path.length();
  CHECK((path.pose(L - 1e-7).translation() - first.translation()).norm() < 1e-6);
}

TEST_CASE("a loop of two laps passes its start at half the frames and drives the same track again") {
  rgbl::SyntheticOptions options;
  options.frames = 241;  // 240 m: two laps of 120 m
  options.path.kind = rgbl::PathKind::loop;
  options.path.loop_laps = 2;
  const rgbl::SyntheticGenerator generator(options);
  CHECK_THAT(generator.path().length(), WithinAbs(120.0, 1e-9));
  for (int i = 0; i <= 120; ++i) {
    const Eigen::Isometry3d first = generator.pose(i), second = generator.pose(i + 120);
    REQUIRE((second.translation() - first.translation()).norm() < 1e-9);
    REQUIRE(rgbl::rotation_angle(second.linear() * first.linear().transpose()) < 1e-9);
  }
  CHECK(generator.pose(60).translation().norm() > 30.0);  // it went round in between
  // the corners must fit into one lap, not into the distance driven
  options.frames = 120;
  CHECK_THROWS_WITH(options.validate(), Contains("frames"));
  options.path.loop_laps = 0;
  CHECK_THROWS_WITH(options.validate(), Contains("path.loop_laps"));
}

TEST_CASE("a loop's later laps a lane to the side: the same track shifted, a smooth lane change before the start") {
  rgbl::SyntheticOptions options;
  options.frames = 241;  // two laps of 120 m
  options.path.kind = rgbl::PathKind::loop;
  options.path.loop_laps = 2;
  const rgbl::SyntheticGenerator same(options);
  options.path.loop_lap_offset = -3.3;  // the next lane to the left
  const rgbl::SyntheticGenerator offset(options);
  const rgbl::DrivePath& path = offset.path();
  // the first lap up to the lane change (it starts 40 m before the start) is the plain loop's, to the bit
  for (int i = 0; i < 80; ++i) REQUIRE(offset.pose(i).isApprox(same.pose(i), 0.0));
  // after the change (it ends 10 m before the start) every pose is the plain one moved 3.3 m left,
  // with the same heading
  for (int i = 111; i <= 240; ++i) {
    const Eigen::Isometry3d a = same.pose(i), b = offset.pose(i);
    const Eigen::Vector3d left = -a.linear().col(0);  // the camera's -x axis
    REQUIRE((b.translation() - (a.translation() + 3.3 * left)).norm() < 1e-9);
    REQUIRE(rgbl::rotation_angle(b.linear() * a.linear().transpose()) < 1e-6);
  }
  // in between the offset grows smoothly and the camera points where it moves
  double previous = 0.0;
  for (int i = 80; i <= 110; ++i) {
    const double s = i * options.step();
    const double o = path.camera_offset(s);
    REQUIRE(o <= previous + 1e-12);
    REQUIRE(previous - o < 3.3 * 1.5 / 30.0 + 1e-9);  // the smoothstep's steepest slope, per metre
    previous = o;
    const Eigen::Vector3d motion = offset.pose_at((i + 0.01) * options.frame_period).translation() -
                                   offset.pose_at((i - 0.01) * options.frame_period).translation();
    REQUIRE(std::acos(motion.normalized().dot(offset.pose(i).linear().col(2))) < 1e-4);
  }
  CHECK(previous == -3.3);
  // a lane outside the road, or a change longer than the lap, is refused
  options.path.loop_lap_offset = 1.0;  // 1.65 m right of the centreline + 1 m: into the parking lane
  CHECK_THROWS_WITH(options.validate(), Contains("path.loop_lap_offset"));
  options.path.loop_lap_offset = -3.3;
  options.path.loop_lap_change = 110.0;
  CHECK_THROWS_WITH(rgbl::SyntheticGenerator(options), Contains("path.loop_lap_change"));
}

TEST_CASE("a loop needs enough frames for its corners") {
  rgbl::SyntheticOptions options;
  options.path.kind = rgbl::PathKind::loop;
  options.frames = 40;  // 39 m < 2 pi 15 m
  CHECK_THROWS_AS(options.validate(), rgbl::ConfigError);
  CHECK_THROWS_WITH(options.validate(), Contains("frames"));
  options.path.loop_corner_radius = 5.0;
  CHECK_THROWS_WITH(options.validate(), Contains("path.loop_corner_radius"));
}
