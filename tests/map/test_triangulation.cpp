#include "map/points_map.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/map/triangulation.hpp"

#include <catch2/catch.hpp>

#include <cmath>

namespace {

// Two keyframes of the points scene (0.5 m apart sideways, points 6-14 m ahead); the first
// `with_depth` points keep their depth and become landmarks seen by both (the covisibility that
// triangulation searches), the rest have no depth, as far points without a LiDAR return.
struct TwoViews {
  rgbl::test::PointsMap scene;
  rgbl::Map map;
  rgbl::KeyframeId a, b;
};

void make_two_views(TwoViews& t, int count, std::size_t with_depth) {
  t.scene = rgbl::test::make_points_map(2, count);
  rgbl::Keyframe ka = rgbl::test::make_points_keyframe(t.scene, 0, t.scene.T_cam_world[0]);
  rgbl::Keyframe kb = rgbl::test::make_points_keyframe(t.scene, 1, t.scene.T_cam_world[1]);
  rgbl::test::drop_depth(t.scene, 0, with_depth, ka);
  rgbl::test::drop_depth(t.scene, 1, with_depth, kb);
  t.a = t.map.add_keyframe(std::move(ka));
  t.b = t.map.add_keyframe(std::move(kb));
  rgbl::test::add_shared_landmarks(t.scene, with_depth, t.map);
}

// Points without depth that both keyframes see: what triangulation can make.
int seen_by_both(const TwoViews& t, std::size_t first) {
  int n = 0;
  for (std::size_t i = first; i < t.scene.points.size(); ++i) {
    n += t.scene.keypoint_of_point[0][i] >= 0 && t.scene.keypoint_of_point[1][i] >= 0 ? 1 : 0;
  }
  return n;
}

}  // namespace

TEST_CASE("triangulation: keypoints without depth become landmarks at their points") {
  TwoViews t;
  make_two_views(t, 120, 20);
  const int expected = seen_by_both(t, 20);
  REQUIRE(expected > 60);
  const std::size_t before = t.map.landmark_count();
  const auto created = rgbl::triangulate_landmarks(t.map, t.scene.camera, t.b);
  CHECK(static_cast<int>(created.size()) == expected);
  CHECK(t.map.landmark_count() == before + created.size());
  double worst = 0.0;
  for (const rgbl::LandmarkId id : created) {
    const rgbl::Landmark& l = *t.map.landmark(id);
    REQUIRE(l.observations.size() == 2);
    const int kpb = l.observations.at(t.b);
    // the point whose keypoint in b this is
    std::size_t point = t.scene.points.size();
    for (std::size_t i = 0; i < t.scene.points.size(); ++i) {
      if (t.scene.keypoint_of_point[1][i] == kpb) point = i;
    }
    REQUIRE(point < t.scene.points.size());
    CHECK(l.observations.at(t.a) == t.scene.keypoint_of_point[0][point]);
    CHECK(t.map.keyframe(t.b)->landmarks[static_cast<std::size_t>(kpb)] == id);
    worst = std::max(worst, (l.position - t.scene.points[point]).norm());
  }
  // keypoints are floats: 1e-5 px at 500 px focal length and 14 m is well under a millimetre
  CHECK(worst < 1e-3);
  // everything open is taken: a second pass makes nothing
  CHECK(rgbl::triangulate_landmarks(t.map, t.scene.camera, t.b).empty());
}

TEST_CASE("triangulation: no point off the epipolar line, with another descriptor, next to something moving or without parallax") {
  TwoViews t;
  make_two_views(t, 120, 20);
  const int expected = seen_by_both(t, 20);
  // three points seen by both, each broken one way in b
  std::vector<std::size_t> broken;
  for (std::size_t i = 20; i < t.scene.points.size() && broken.size() < 3; ++i) {
    if (t.scene.keypoint_of_point[0][i] >= 0 && t.scene.keypoint_of_point[1][i] >= 0) broken.push_back(i);
  }
  REQUIRE(broken.size() == 3);
  rgbl::Keyframe& kb = *t.map.keyframe(t.b);
  const auto k0 = static_cast<std::size_t>(t.scene.keypoint_of_point[1][broken[0]]);
  const auto k1 = static_cast<std::size_t>(t.scene.keypoint_of_point[1][broken[1]]);
  const auto k2 = static_cast<std::size_t>(t.scene.keypoint_of_point[1][broken[2]]);
  // the cameras move along x: epipolar lines run along the rows, 4 px down is 4 sigmas off
  kb.keypoints[k0].y += 4.0F;
  for (std::size_t byte = 0; byte < 8; ++byte) kb.descriptors[k1][byte] ^= 0xFF;  // 64 bits away
  // a keypoint 2 px away with a depth but no sigma: the tracker found it moving
  rgbl::Keypoint moving = kb.keypoints[k2];
  moving.x += 2.0F;
  kb.keypoints.push_back(moving);
  kb.descriptors.push_back(rgbl::Descriptor{});
  kb.depth.push_back(9.0F);
  kb.depth_sigma.push_back(0.0F);
  kb.landmarks.emplace_back();

  // a radius that reaches the moving keypoint and no other open one (the points are random)
  rgbl::TriangulationOptions options;
  options.moving_radius_px = 3.0;
  const auto created = rgbl::triangulate_landmarks(t.map, t.scene.camera, t.b, options);
  CHECK(static_cast<int>(created.size()) == expected - 3);
  for (const std::size_t k : {k0, k1, k2}) CHECK_FALSE(t.map.keyframe(t.b)->landmarks[k].valid());

  SECTION("rays closer than the minimum parallax make nothing") {
    TwoViews u;
    make_two_views(u, 120, 20);
    rgbl::TriangulationOptions strict;
    strict.min_parallax_deg = 6.0;  // 0.5 m at 6 m ahead is at most 4.8 deg
    CHECK(rgbl::triangulate_landmarks(u.map, u.scene.camera, u.b, strict).empty());
    strict.min_parallax_deg = 1.0;
    strict.min_baseline_ratio = 0.1;  // 0.5 m against a median depth of about 10 m
    CHECK(rgbl::triangulate_landmarks(u.map, u.scene.camera, u.b, strict).empty());
    // the depth's sigma: sqrt(2) px at 500 px over at most 4.8 deg is at least 1.7 % of the depth
    strict.min_baseline_ratio = 0.0;
    strict.max_depth_sigma_relative = 0.016;
    CHECK(rgbl::triangulate_landmarks(u.map, u.scene.camera, u.b, strict).empty());
    strict.max_depth_sigma_relative = 0.05;  // 3.2 deg and more: only the points within about 9 m
    const auto some = rgbl::triangulate_landmarks(u.map, u.scene.camera, u.b, strict);
    CHECK(!some.empty());
    CHECK(static_cast<int>(some.size()) < expected);
  }
}

TEST_CASE("triangulation: options are validated with the key named") {
  rgbl::TriangulationOptions o;
  CHECK_NOTHROW(o.validate());
  o.min_parallax_deg = 0.0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("triangulation.min_parallax_deg"));
  o = {};
  o.max_ratio = 1.5;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("triangulation.max_ratio"));
  o = {};
  o.min_depth = 0.0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("triangulation.min_depth"));
}
