#include "rgbl/map/map.hpp"

#include <catch2/catch.hpp>

namespace {

rgbl::Keyframe make_keyframe(double z, int keypoints) {
  rgbl::Keyframe kf;
  kf.T_cam_world = Eigen::Isometry3d::Identity();
  kf.T_cam_world.translation() = Eigen::Vector3d(0.0, 0.0, -z);  // camera at world z
  for (int i = 0; i < keypoints; ++i) {
    rgbl::Keypoint kp;
    kp.x = 10.0F * static_cast<float>(i);
    kp.y = 5.0F;
    kp.level = i % 3;
    kf.keypoints.push_back(kp);
    rgbl::Descriptor d{};
    d[0] = static_cast<std::uint8_t>(i);
    kf.descriptors.push_back(d);
  }
  return kf;
}

}  // namespace

TEST_CASE("map: observations, covisibility and spanning tree") {
  rgbl::Map map;
  const auto a = map.add_keyframe(make_keyframe(0.0, 10));
  const auto b = map.add_keyframe(make_keyframe(1.0, 10));
  const auto c = map.add_keyframe(make_keyframe(2.0, 10));
  REQUIRE(map.keyframe_count() == 3);
  // a-b share 4 landmarks, b-c share 2, a-c share 1
  std::vector<rgbl::LandmarkId> l;
  for (int i = 0; i < 6; ++i) l.push_back(map.add_landmark(Eigen::Vector3d(0.0, 0.0, 10.0 + i), a));
  for (int i = 0; i < 4; ++i) {
    map.add_observation(l[static_cast<std::size_t>(i)], a, i);
    map.add_observation(l[static_cast<std::size_t>(i)], b, i);
  }
  map.add_observation(l[4], b, 4);
  map.add_observation(l[4], c, 4);
  map.add_observation(l[5], b, 5);
  map.add_observation(l[5], c, 5);
  map.add_observation(l[5], a, 5);
  for (const auto k : {a, b, c}) map.update_covisibility(k);
  CHECK(map.keyframe(b)->covisibility.at(a) == 5);
  CHECK(map.keyframe(b)->covisibility.at(c) == 2);
  CHECK(map.keyframe(a)->covisibility.at(c) == 1);
  CHECK(map.best_covisible(b, 1) == std::vector<rgbl::KeyframeId>{a});
  CHECK(map.best_covisible(b, 5, 2) == std::vector<rgbl::KeyframeId>{a, c});
  CHECK(map.neighbourhood(b, 5) == std::vector<rgbl::KeyframeId>{b, a, c});
  CHECK(map.neighbourhood(c, 1) == std::vector<rgbl::KeyframeId>{c, b});
  CHECK(map.keyframe(b)->parent == a);
  CHECK(map.keyframe(c)->parent == b);
  CHECK(map.keyframe(b)->landmark_count() == 6);
  CHECK(map.keyframe(b)->tracked_landmarks(3, map) == 1);

  SECTION("a keypoint holds one landmark; re-observing moves the slot") {
    map.add_observation(l[0], c, 7);
    map.add_observation(l[0], c, 8);
    CHECK_FALSE(map.keyframe(c)->landmarks[7].valid());
    CHECK(map.keyframe(c)->landmarks[8] == l[0]);
    CHECK(map.landmark(l[0])->observations.at(c) == 8);
  }
  SECTION("the last observation gone erases the landmark") {
    map.erase_observation(l[4], b);
    CHECK(map.landmark(l[4]) != nullptr);
    map.erase_observation(l[4], c);
    CHECK(map.landmark(l[4]) == nullptr);
    CHECK_FALSE(map.keyframe(c)->landmarks[4].valid());
    CHECK(map.landmark_count() == 5);
  }
  SECTION("erasing a keyframe re-attaches its children and keeps its pose") {
    const Eigen::Isometry3d pose_b = map.keyframe(b)->T_cam_world;
    map.erase_keyframe(b);
    CHECK(map.keyframe(b) == nullptr);
    CHECK(map.keyframe(c)->parent == a);
    CHECK(map.keyframe(a)->covisibility.count(b) == 0);
    for (const auto id : l) {
      if (const auto* lm = map.landmark(id)) CHECK(lm->observations.count(b) == 0);
    }
    // landmarks 0..3 keep their observation in a; landmark 4 keeps c
    CHECK(map.landmark(l[0])->observations.size() == 1);
    REQUIRE(map.keyframe_pose(b).has_value());
    CHECK((map.keyframe_pose(b)->matrix() - pose_b.matrix()).norm() < 1e-12);
    // Moving the parent moves the erased keyframe's pose with it.
    map.keyframe(a)->T_cam_world.translation().x() = 0.5;
    CHECK(map.keyframe_pose(b)->translation().x() == Approx(0.5));
  }
  SECTION("fusing duplicates moves observations to the survivor") {
    map.replace_landmark(l[4], l[0]);
    CHECK(map.landmark(l[4]) == nullptr);
    const auto* survivor = map.landmark(l[0]);
    CHECK(survivor->observations.count(c) == 1);
    CHECK(map.keyframe(c)->landmarks[4] == l[0]);
    CHECK(survivor->observations.at(b) == 0);  // b already saw l[0]: its own observation is kept
  }
}

TEST_CASE("map: representative descriptor, viewing direction and distance range") {
  rgbl::Map map(rgbl::MapOptions{8, 1.2});
  std::vector<rgbl::KeyframeId> kfs;
  for (int k = 0; k < 3; ++k) kfs.push_back(map.add_keyframe(make_keyframe(static_cast<double>(k), 4)));
  // descriptors 0xFF, 0x01, 0x03 in byte 0: medians of distances 6, 1, 1: the outlier 0xFF is never
  // representative, ties go to the first
  map.keyframe(kfs[0])->descriptors[1] = rgbl::Descriptor{};
  map.keyframe(kfs[0])->descriptors[1][0] = 0xFF;
  map.keyframe(kfs[1])->descriptors[1] = rgbl::Descriptor{};
  map.keyframe(kfs[1])->descriptors[1][0] = 0x01;
  map.keyframe(kfs[2])->descriptors[1] = rgbl::Descriptor{};
  map.keyframe(kfs[2])->descriptors[1][0] = 0x03;
  const auto l = map.add_landmark(Eigen::Vector3d(0.0, 0.0, 20.0), kfs[0]);
  for (const auto k : kfs) map.add_observation(l, k, 1);
  map.update_landmark(l);
  const auto* lm = map.landmark(l);
  CHECK(lm->descriptor[0] == 0x01);
  CHECK((lm->normal - Eigen::Vector3d::UnitZ()).norm() < 1e-12);
  // reference keyframe at z = 0 sees it at 20 m on level 1
  CHECK(lm->max_distance == Approx(20.0 * 1.2));
  CHECK(lm->min_distance == Approx(20.0 * 1.2 / std::pow(1.2, 7)));
  CHECK(lm->predict_level(lm->max_distance, 8, 1.2) == 0);
  CHECK(lm->predict_level(20.0, 8, 1.2) == 1);
}

TEST_CASE("map: ids are stable and never reused") {
  rgbl::Map map;
  const auto a = map.add_landmark(Eigen::Vector3d::Zero(), rgbl::KeyframeId{});
  map.erase_landmark(a);
  const auto b = map.add_landmark(Eigen::Vector3d::Zero(), rgbl::KeyframeId{});
  CHECK(a != b);
  CHECK(map.landmark(a) == nullptr);
  CHECK(map.landmark_ids() == std::vector<rgbl::LandmarkId>{b});
}

TEST_CASE("map: erasing a keyframe carries the motion measured into it on to the keyframe after it") {
  rgbl::Map map;
  const auto a = map.add_keyframe(make_keyframe(0.0, 4));
  rgbl::Keyframe kb = make_keyframe(1.0, 4);
  kb.previous = a;
  kb.T_cam_previous = Eigen::Isometry3d(Eigen::Translation3d(0.1, 0.0, -1.0)) *
                      Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY());
  const Eigen::Isometry3d T_b_a = kb.T_cam_previous;
  kb.T_cam_previous_lidar = Eigen::Translation3d(0.0, 0.0, 0.01) * T_b_a;  // the scans' own measure
  const Eigen::Isometry3d T_b_a_lidar = *kb.T_cam_previous_lidar;
  const auto b = map.add_keyframe(std::move(kb));
  rgbl::Keyframe kc = make_keyframe(2.0, 4);
  kc.previous = b;
  kc.T_cam_previous = Eigen::Isometry3d(Eigen::Translation3d(-0.05, 0.01, -1.2)) *
                      Eigen::AngleAxisd(-0.03, Eigen::Vector3d::UnitY());
  const Eigen::Isometry3d T_c_b = kc.T_cam_previous;
  kc.T_cam_previous_lidar = Eigen::Translation3d(0.0, 0.0, -0.01) * T_c_b;
  const Eigen::Isometry3d T_c_b_lidar = *kc.T_cam_previous_lidar;
  const auto c = map.add_keyframe(std::move(kc));
  CHECK(map.keyframe(c)->previous == b);
  map.erase_keyframe(b);
  CHECK(map.keyframe(c)->previous == a);
  CHECK(map.keyframe(c)->T_cam_previous.isApprox(T_c_b * T_b_a, 1e-12));
  REQUIRE(map.keyframe(c)->T_cam_previous_lidar);
  CHECK(map.keyframe(c)->T_cam_previous_lidar->isApprox(T_c_b_lidar * T_b_a_lidar, 1e-12));
  map.erase_keyframe(a);  // a map's first has none before it: nor has c now
  CHECK_FALSE(map.keyframe(c)->previous.valid());
}

TEST_CASE("map: erasing a keyframe drops the scans' motion after it when its own was not measured") {
  rgbl::Map map;
  const auto a = map.add_keyframe(make_keyframe(0.0, 4));
  rgbl::Keyframe kb = make_keyframe(1.0, 4);
  kb.previous = a;  // its scans were not registered (no clear optimum)
  const auto b = map.add_keyframe(std::move(kb));
  rgbl::Keyframe kc = make_keyframe(2.0, 4);
  kc.previous = b;
  kc.T_cam_previous_lidar = Eigen::Isometry3d(Eigen::Translation3d(0.0, 0.0, -1.0));
  const auto c = map.add_keyframe(std::move(kc));
  map.erase_keyframe(b);
  CHECK(map.keyframe(c)->previous == a);
  CHECK_FALSE(map.keyframe(c)->T_cam_previous_lidar);
}
