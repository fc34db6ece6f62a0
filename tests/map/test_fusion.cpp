#include "map/points_map.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/map/fusion.hpp"
#include "rgbl/map/landmark_view.hpp"

#include <catch2/catch.hpp>

#include <cmath>

namespace {

// Landmarks for keyframe `k` of the scene: one per point it sees, at the point moved by `offset`.
std::vector<rgbl::LandmarkId> add_landmarks(rgbl::Map& map, rgbl::test::PointsMap& s, rgbl::KeyframeId k,
                                            std::size_t first, std::size_t last, const Eigen::Vector3d& offset) {
  std::vector<rgbl::LandmarkId> ids(s.points.size());
  for (std::size_t i = first; i < last; ++i) {
    const int keypoint = s.keypoint_of_point[static_cast<std::size_t>(k.value)][i];
    if (keypoint < 0) continue;
    ids[i] = map.add_landmark(s.points[i] + offset, k);
    map.add_observation(ids[i], k, keypoint);
    map.update_landmark(ids[i]);
  }
  return ids;
}

}  // namespace

TEST_CASE("fusion: a second copy of every landmark is merged, unseen points gain the observation") {
  rgbl::test::PointsMap s = rgbl::test::make_points_map(2, 60);
  rgbl::Map map;
  const auto a = map.add_keyframe(rgbl::test::make_points_keyframe(s, 0, s.T_cam_world[0]));
  const auto b = map.add_keyframe(rgbl::test::make_points_keyframe(s, 1, s.T_cam_world[1]));
  // a sees every point; b holds its own duplicates of the first 30 (2 cm off) and nothing for the rest
  const auto of_a = add_landmarks(map, s, a, 0, s.points.size(), Eigen::Vector3d::Zero());
  const auto of_b = add_landmarks(map, s, b, 0, 30, Eigen::Vector3d(0.02, 0.0, 0.0));
  // one of b's keypoints carries a descriptor 64 bits away from its point's: not the same landmark
  const std::size_t changed = 45;
  const int changed_keypoint = s.keypoint_of_point[1][changed];
  REQUIRE(changed_keypoint >= 0);
  for (std::size_t byte = 0; byte < 8; ++byte) map.keyframe(b)->descriptors[static_cast<std::size_t>(changed_keypoint)][byte] ^= 0xFF;

  std::vector<rgbl::LandmarkId> landmarks;
  for (const auto l : of_a) {
    if (l.valid()) landmarks.push_back(l);
  }
  int seen_by_both = 0, seen_by_b_only = 0;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (s.keypoint_of_point[1][i] >= 0 && s.keypoint_of_point[0][i] >= 0) ++seen_by_both;
    if (s.keypoint_of_point[1][i] >= 0 && s.keypoint_of_point[0][i] < 0) ++seen_by_b_only;
  }
  REQUIRE(seen_by_b_only == 0);
  const std::size_t landmarks_before = map.landmark_count();
  const int fused = rgbl::fuse_landmarks(map, s.camera, b, landmarks);
  CHECK(fused == seen_by_both - 1);  // all but the changed descriptor

  const rgbl::Keyframe& kb = *map.keyframe(b);
  const rgbl::Keyframe& ka = *map.keyframe(a);
  int duplicates_left = 0;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const int kpb = s.keypoint_of_point[1][i];
    if (kpb < 0) continue;
    const rgbl::LandmarkId in_b = kb.landmarks[static_cast<std::size_t>(kpb)];
    const rgbl::LandmarkId in_a = ka.landmarks[static_cast<std::size_t>(s.keypoint_of_point[0][i])];
    if (i == changed) {
      CHECK_FALSE(in_b.valid());
      continue;
    }
    CHECK(in_b == in_a);  // one landmark, seen from both
    if (of_b[i].valid() && map.landmark(of_b[i]) != nullptr) ++duplicates_left;
  }
  CHECK(duplicates_left == 0);
  // each of b's 30 duplicates merged away (ties keep a's, the target's copy goes)
  CHECK(map.landmark_count() == landmarks_before - 30);
  // fusing again finds nothing new
  CHECK(rgbl::fuse_landmarks(map, s.camera, b, landmarks) == 0);
}

TEST_CASE("fusion: a landmark far from where its keypoint is does not fuse") {
  rgbl::test::PointsMap s = rgbl::test::make_points_map(2, 20);
  rgbl::Map map;
  const auto a = map.add_keyframe(rgbl::test::make_points_keyframe(s, 0, s.T_cam_world[0]));
  const auto b = map.add_keyframe(rgbl::test::make_points_keyframe(s, 1, s.T_cam_world[1]));
  // a's landmarks 0.3 m to the side: ~15 px at 10 m, outside the 3 px radius
  std::vector<rgbl::LandmarkId> landmarks;
  for (const auto l : add_landmarks(map, s, a, 0, s.points.size(), Eigen::Vector3d(0.3, 0.0, 0.0))) {
    if (l.valid()) landmarks.push_back(l);
  }
  CHECK(rgbl::fuse_landmarks(map, s.camera, b, landmarks) == 0);
  rgbl::FusionOptions wide;
  wide.radius_px = 40.0;  // the search window reaches them, the reprojection chi2 (1 px sigma) still refuses
  CHECK(rgbl::fuse_landmarks(map, s.camera, b, landmarks, wide) == 0);
}

TEST_CASE("fusion: options are checked") {
  rgbl::FusionOptions o;
  CHECK_NOTHROW(o.validate());
  o.radius_px = 0.0;
  CHECK_THROWS_AS(o.validate(), rgbl::ConfigError);
  o = {};
  o.max_hamming = 300;
  CHECK_THROWS_AS(o.validate(), rgbl::ConfigError);
  o = {};
  o.min_view_cos = 1.5;
  CHECK_THROWS_AS(o.validate(), rgbl::ConfigError);
}

TEST_CASE("landmark view: pixel, distance and level where it is visible, nothing where it is not") {
  const rgbl::PinholeCamera camera{.fx = 500.0, .fy = 500.0, .cx = 320.0, .cy = 240.0, .width = 640, .height = 480};
  const rgbl::MapOptions map_options;  // 8 levels, scale 1.2
  rgbl::Landmark l;
  l.position = Eigen::Vector3d(1.0, 0.5, 10.0);
  l.normal = Eigen::Vector3d::UnitZ();  // it was seen looking along +z
  l.min_distance = 5.0;
  l.max_distance = 20.0;
  const Eigen::Isometry3d at_origin = Eigen::Isometry3d::Identity();
  const auto seen = rgbl::view_landmark(l, at_origin, Eigen::Vector3d::Zero(), camera, map_options, 0.5);
  REQUIRE(seen.has_value());
  CHECK(seen->pixel.x() == Approx(370.0));
  CHECK(seen->pixel.y() == Approx(265.0));
  CHECK(seen->distance == Approx(l.position.norm()));
  CHECK(seen->level == l.predict_level(seen->distance, map_options.levels, map_options.scale_factor));

  // behind the camera: turned round
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  CHECK_FALSE(rgbl::view_landmark(l, turned, Eigen::Vector3d::Zero(), camera, map_options, 0.5));
  // too near for the distances it was seen from (0.8 x 5 m = 4 m): a camera 7 m closer
  Eigen::Isometry3d near = Eigen::Isometry3d::Identity();
  near.translation() = Eigen::Vector3d(0.0, 0.0, -7.0);
  CHECK_FALSE(rgbl::view_landmark(l, near, Eigen::Vector3d(0.0, 0.0, 7.0), camera, map_options, 0.5));
  // seen from 70 deg off its viewing direction (cos 0.34), looking straight at it from 10 m: refused at
  // min_view_cos 0.5, taken at 0.3
  const double angle = 70.0 * M_PI / 180.0;
  Eigen::Isometry3d T_world_side = Eigen::Isometry3d::Identity();
  T_world_side.linear() = Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitY()).toRotationMatrix();  // z to the landmark
  const Eigen::Vector3d side = l.position - 10.0 * T_world_side.linear().col(2);
  T_world_side.translation() = side;
  CHECK_FALSE(rgbl::view_landmark(l, T_world_side.inverse(), side, camera, map_options, 0.5));
  const auto oblique = rgbl::view_landmark(l, T_world_side.inverse(), side, camera, map_options, 0.3);
  REQUIRE(oblique.has_value());
  CHECK(oblique->pixel.x() == Approx(320.0));
  CHECK(oblique->pixel.y() == Approx(240.0));
  CHECK(oblique->distance == Approx(10.0));
}
