#include "map/points_map.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/tracking/local_mapping.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <utility>
#include <vector>

namespace {

struct Pose {
  double x = 0.0;        // camera centre on the world's x axis, m
  double yaw_deg = 0.0;  // about the camera's y axis; 0 looks along +z
};

struct Mapped {
  std::vector<int> ids;  // the keyframes still in the map
  int culled_revisited = 0;
};

// Keyframes at the given poses, all observing exact landmarks on the plane z = 10 m (so a camera
// looking along +z has every keypoint depth 10 m, and the place radius is 1 m at the defaults); then
// local mapping of the last keyframe with only the revisit rule able to cull (ORB-SLAM's redundancy
// rule is switched off by a ratio it cannot exceed).
Mapped keyframes_after_mapping(const std::vector<Pose>& poses, rgbl::LocalMappingOptions options) {
  rgbl::test::PointsMap s = rgbl::test::make_points_map(0, 400, 11);
  for (Eigen::Vector3d& p : s.points) p.z() = 10.0;
  for (const Pose& p : poses) {
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    T_world_cam.linear() = Eigen::AngleAxisd(p.yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY()).matrix();
    T_world_cam.translation() = Eigen::Vector3d(p.x, 0.0, 0.0);
    s.T_cam_world.push_back(T_world_cam.inverse());
  }
  rgbl::Map map;
  std::vector<rgbl::LandmarkId> landmark(s.points.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const rgbl::KeyframeId id = map.add_keyframe(rgbl::test::make_points_keyframe(s, static_cast<int>(k), s.T_cam_world[k]));
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const int keypoint = s.keypoint_of_point[k][i];
      if (keypoint < 0) continue;
      if (!landmark[i].valid()) landmark[i] = map.add_landmark(s.points[i], id);
      map.add_observation(landmark[i], id, keypoint);
    }
    if (k + 1 < poses.size()) map.update_covisibility(id);
  }
  options.redundant_ratio = 1.0;
  options.local_ba = false;
  options.fusion = false;
  options.max_new_depth_points = 0;
  rgbl::LocalMapper mapper(map, s.camera, options);
  const rgbl::LocalMappingStats stats = mapper.process(map.last_keyframe_id());
  CHECK(stats.culled_keyframes == stats.culled_revisited);
  Mapped out{{}, stats.culled_revisited};
  for (const rgbl::KeyframeId id : map.keyframe_ids()) out.ids.push_back(id.value);
  return out;
}

}  // namespace

TEST_CASE("revisit culling: a place passed three times keeps its first keyframe and the newest") {
  // Out 6 m along x, back to x = 1.6 (keyframe 5), out to 4.4, back to 1.7 (keyframe 7): keyframes 1
  // and 5 are 0.2 and 0.1 m from keyframe 7, after drives of 8.9 and 5.5 m along the keyframes
  // (>= 3 x the 1 m radius); keyframe 2 (x = 3) is 1.3 m away.
  const std::vector<Pose> three_passes = {{0.0}, {1.5}, {3.0}, {4.5}, {6.0}, {1.6}, {4.4}, {1.7}};
  const Mapped mapped = keyframes_after_mapping(three_passes, rgbl::LocalMappingOptions{});
  CHECK(mapped.ids == std::vector<int>{0, 1, 2, 3, 4, 6, 7});
  CHECK(mapped.culled_revisited == 1);
  // Three per place: all stay.
  rgbl::LocalMappingOptions three;
  three.max_keyframes_per_place = 3;
  CHECK(keyframes_after_mapping(three_passes, three).ids == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7});
  // Two passes: the place holds two keyframes, both stay.
  CHECK(keyframes_after_mapping({{0.0}, {1.5}, {3.0}, {4.5}, {6.0}, {1.7}}, rgbl::LocalMappingOptions{}).ids ==
        std::vector<int>{0, 1, 2, 3, 4, 5});
  // Switched off, the three passes keep every keyframe.
  rgbl::LocalMappingOptions off;
  off.place_culling = false;
  CHECK(keyframes_after_mapping(three_passes, off).ids == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7});
}

TEST_CASE("revisit culling: the same place seen in another direction, or the keyframes just before, stay") {
  // Keyframe 5 at the place but turned by 20 deg (beyond place_angle_deg 10); at 5 deg it goes.
  CHECK(keyframes_after_mapping({{0.0}, {1.5}, {3.0}, {4.5}, {6.0}, {1.6, 20.0}, {4.4}, {1.7}},
                                rgbl::LocalMappingOptions{}).ids == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7});
  CHECK(keyframes_after_mapping({{0.0}, {1.5}, {3.0}, {4.5}, {6.0}, {1.6, 5.0}, {4.4}, {1.7}},
                                rgbl::LocalMappingOptions{}).ids == std::vector<int>{0, 1, 2, 3, 4, 6, 7});
  // A slow drive: keyframes 0.4 m apart are within the radius but only 0.4-0.8 m of driving back.
  CHECK(keyframes_after_mapping({{0.0}, {0.4}, {0.8}, {1.2}, {1.6}, {2.0}}, rgbl::LocalMappingOptions{}).ids ==
        std::vector<int>{0, 1, 2, 3, 4, 5});
}

TEST_CASE("revisit culling options are checked, naming the field") {
  rgbl::LocalMappingOptions o;
  o.place_distance_ratio = 0.0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("local_mapping.place_distance_ratio"));
  o = {};
  o.place_angle_deg = 90.0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("local_mapping.place_angle_deg"));
  o = {};
  o.revisit_path_ratio = 0.5;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("local_mapping.revisit_path_ratio"));
  o = {};
  o.max_keyframes_per_place = 1;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("local_mapping.max_keyframes_per_place"));
}

TEST_CASE("local mapping checks its keyframe pair options (naming the field)") {
  rgbl::LocalMappingOptions o;
  o.pairs.road_sigma_tilt_deg = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("keyframe_pairs.road_sigma_tilt_deg"));
  o = {};
  o.pairs.odometry_sigma_translation = -0.05;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("keyframe_pairs.odometry_sigma_translation"));
}

namespace {

// Three keyframes 0.5 m apart; the first keyframe's landmarks are all its keypoints' points, the
// later two observe only the even ones. Points 0-9 were predicted visible in 13 frames and found in
// one (a car driving ahead: it keeps its place in the image, not in the world), the rest found in 8 of
// 10. Returns which of the first keyframe's landmarks are left after local mapping of the later two.
struct FirstKeyframeCulling {
  int car_left = 0, static_left = 0, seen_once_left = 0;
};
FirstKeyframeCulling cull_after_first_keyframe(bool watched) {
  rgbl::test::PointsMap s = rgbl::test::make_points_map(3, 60, 5);
  rgbl::Map map;
  std::vector<rgbl::LandmarkId> landmark(s.points.size());
  const rgbl::KeyframeId first = map.add_keyframe(rgbl::test::make_points_keyframe(s, 0, s.T_cam_world[0]));
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const int keypoint = s.keypoint_of_point[0][i];
    if (keypoint < 0) continue;
    landmark[i] = map.add_landmark(s.points[i], first);
    map.add_observation(landmark[i], first, keypoint);
    map.landmark(landmark[i])->visible = i < 10 ? 13 : 10;
    map.landmark(landmark[i])->found = i < 10 ? 1 : 8;
  }
  map.update_covisibility(first);
  rgbl::LocalMappingOptions options;
  options.local_ba = false;
  options.fusion = false;
  options.keyframe_culling = false;
  options.max_new_depth_points = 0;
  rgbl::LocalMapper mapper(map, s.camera, options);
  if (watched) mapper.watch_initial(first);
  for (int k = 1; k < 3; ++k) {
    const rgbl::KeyframeId id = map.add_keyframe(rgbl::test::make_points_keyframe(s, k, s.T_cam_world[static_cast<std::size_t>(k)]));
    for (std::size_t i = 0; i < s.points.size(); i += 2) {
      const int keypoint = s.keypoint_of_point[static_cast<std::size_t>(k)][i];
      if (keypoint < 0 || !landmark[i].valid()) continue;
      map.keyframe(id)->landmarks[static_cast<std::size_t>(keypoint)] = landmark[i];
      map.add_observation(landmark[i], id, keypoint);
    }
    mapper.process(id);
  }
  FirstKeyframeCulling left;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (!landmark[i].valid() || map.landmark(landmark[i]) == nullptr) continue;
    if (i < 10) {
      ++left.car_left;
    } else if (i % 2 == 0) {
      ++left.static_left;
    } else {
      ++left.seen_once_left;
    }
  }
  return left;
}

}  // namespace

TEST_CASE("the first keyframe's landmarks are culled by their found ratio, not by their observations") {
  const FirstKeyframeCulling unwatched = cull_after_first_keyframe(false);
  const FirstKeyframeCulling watched = cull_after_first_keyframe(true);
  // every point of the scene is in view of the first keyframe (6-14 m ahead, +-3 m across)
  const int total = unwatched.car_left + unwatched.static_left + unwatched.seen_once_left;
  REQUIRE(total == 60);
  CHECK(unwatched.car_left == 10);  // without it nothing of the first keyframe is ever culled
  CHECK(watched.car_left == 0);
  CHECK(watched.static_left == unwatched.static_left);
  CHECK(watched.static_left == 25);
  // seen by the first keyframe alone, but found whenever predicted: kept (the return of a loop to the
  // drive's start needs them)
  CHECK(watched.seen_once_left == 25);
}

namespace {

// A street in camera-world coordinates (x right, y down, z ahead; the camera 1.65 m above the road):
// the road, and with `landmarks` trunks every 7 m on both sides and a house front every 23 m on the
// left; without them a corridor (the road and two kerb walls), the same at every shift along z.
std::vector<Eigen::Vector3d> street(bool landmarks) {
  std::vector<Eigen::Vector3d> points;
  for (double z = -20.0; z <= 60.0; z += 0.25) {
    for (double x = -8.0; x <= 8.0; x += 0.25) points.emplace_back(x, 1.65, z);
    for (double y = -0.35; y <= 1.65; y += 0.1) {
      points.emplace_back(-8.0, y, z);
      points.emplace_back(8.0, y, z);
    }
  }
  if (!landmarks) return points;
  for (double z = -15.0; z <= 60.0; z += 7.0) {
    for (const double x : {-6.0, 6.0}) {
      for (double y = -3.0; y <= 1.65; y += 0.1) {
        for (double a = 0.0; a < 2.0 * std::numbers::pi; a += std::numbers::pi / 6.0) {
          points.emplace_back(x + 0.15 * std::cos(a), y, z + 0.15 * std::sin(a));
        }
      }
    }
  }
  for (double z0 = -10.0; z0 <= 60.0; z0 += 23.0) {
    for (double z = z0; z <= z0 + 10.0; z += 0.1) {
      for (double y = -5.0; y <= 1.65; y += 0.2) points.emplace_back(-12.0, y, z);
    }
  }
  return points;
}

// Two keyframes 4 m apart on `street`, the second also turned by 1 deg, each with the street's points
// within 40 m as its scan; tracking's motion between them is off by 0.15 m and 0.3 deg. Returns the
// scans' motion local mapping keeps, and the true one.
std::pair<std::optional<Eigen::Isometry3d>, Eigen::Isometry3d> lidar_pair(bool landmarks) {
  const std::vector<Eigen::Vector3d> scene = street(landmarks);
  const Eigen::Isometry3d T_a_world = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_b_world =
      (Eigen::Translation3d(0.0, 0.0, 4.0) * Eigen::AngleAxisd(0.0175, Eigen::Vector3d::UnitY())).inverse();
  const auto scan = [&](const Eigen::Isometry3d& T_cam_world) {
    auto sample = std::make_shared<rgbl::ScanSample>();
    for (const Eigen::Vector3d& p : scene) {
      const Eigen::Vector3d c = T_cam_world * p;
      if (c.norm() > 2.0 && c.norm() < 40.0) sample->points.push_back(c.cast<float>());
    }
    return sample;
  };
  rgbl::Map map;
  rgbl::Keyframe a;
  a.T_cam_world = T_a_world;
  a.scan = scan(T_a_world);
  const rgbl::KeyframeId id_a = map.add_keyframe(std::move(a));
  rgbl::Keyframe b;
  b.T_cam_world = T_b_world;
  b.scan = scan(T_b_world);
  b.previous = id_a;
  const Eigen::Isometry3d T_b_a = T_b_world * T_a_world.inverse();
  b.T_cam_previous = Eigen::Translation3d(0.0, 0.0, 0.15) * Eigen::AngleAxisd(0.005, Eigen::Vector3d::UnitY()) * T_b_a;
  const rgbl::KeyframeId id_b = map.add_keyframe(std::move(b));
  rgbl::LocalMappingOptions options;
  options.local_ba = false;
  options.fusion = false;
  options.keyframe_culling = false;
  options.max_new_depth_points = 0;
  rgbl::PinholeCamera camera;
  camera.fx = camera.fy = 700.0;
  camera.cx = 610.0;
  camera.cy = 185.0;
  camera.width = 1226;
  camera.height = 370;
  rgbl::LocalMapper mapper(map, camera, options);
  mapper.process(id_b);
  // the previous keyframe's scan is released once the new one is registered onto it, the new one's kept
  CHECK_FALSE(map.keyframe(id_a)->scan);
  CHECK(map.keyframe(id_b)->scan);
  return {map.keyframe(id_b)->T_cam_previous_lidar, T_b_a};
}

}  // namespace

TEST_CASE("local mapping registers a keyframe's scan onto the previous one's: the true motion, or none on a corridor") {
  const auto [measured, truth] = lidar_pair(true);
  REQUIRE(measured);
  const Eigen::Isometry3d error = *measured * truth.inverse();
  // tracking's was 0.15 m and 0.29 deg off (0.013 m and 0.00 deg measured: the voxels' means)
  CHECK(error.translation().norm() < 0.03);
  CHECK(Eigen::AngleAxisd(error.linear()).angle() < 0.05 * std::numbers::pi / 180.0);
  // the corridor fits every shift along it equally (the probe loses nothing): not a measurement, no pair
  CHECK_FALSE(lidar_pair(false).first);
}

TEST_CASE("local mapping checks the LiDAR pair's options (naming the field)") {
  rgbl::LocalMappingOptions o;
  o.lidar_max_change_m = 0.0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("local_mapping.lidar_max_change_m"));
  o = {};
  o.lidar_registration.fine_distance = -1.0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("fine_distance"));
}

namespace {

// Five keyframes 0.5 m apart (2 m of baseline) see 200 points 6-14 m ahead. The points right of x =
// 1.5 m are a hedge: each keyframe's depth there is 0.2-0.4 m deep (a different depth each time, as
// leaves return a beam), the others' exact; sigmas 0.05 m. Every landmark starts where its first
// keyframe's depth puts it; local mapping runs twice on the last keyframe (the second BA uses the
// sigmas the first one's landmarks left). Returns the mean landmark error and how many had their
// depth sigmas scaled, of the hedge within 9 m (where 2 m of baseline measure depth to 0.1 m) and of
// the other points.
struct HedgeMapping {
  double hedge_error = 0.0, other_error = 0.0;
  int hedge = 0, other = 0, hedge_scaled = 0, other_scaled = 0;
};
HedgeMapping map_hedge(bool depth_consistency) {
  rgbl::test::PointsMap s = rgbl::test::make_points_map(5, 200, 3);
  const auto in_hedge = [&](std::size_t i) { return s.points[i].x() > 1.5; };
  const auto near_hedge = [&](std::size_t i) { return in_hedge(i) && s.points[i].z() < 9.0; };
  rgbl::Map map;
  std::vector<rgbl::LandmarkId> landmark(s.points.size());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> leaves(0.2, 0.4);
  for (std::size_t k = 0; k < s.T_cam_world.size(); ++k) {
    rgbl::Keyframe kf = rgbl::test::make_points_keyframe(s, static_cast<int>(k), s.T_cam_world[k]);
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const int keypoint = s.keypoint_of_point[k][i];
      if (keypoint >= 0 && in_hedge(i)) kf.depth[static_cast<std::size_t>(keypoint)] += static_cast<float>(leaves(rng));
    }
    const rgbl::KeyframeId id = map.add_keyframe(std::move(kf));
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const int keypoint = s.keypoint_of_point[k][i];
      if (keypoint < 0) continue;
      if (!landmark[i].valid()) {
        const rgbl::Keyframe& first = *map.keyframe(id);
        const auto kp = static_cast<std::size_t>(keypoint);
        const Eigen::Vector3d p_cam =
            s.camera.unproject(Eigen::Vector2d(first.keypoints[kp].x, first.keypoints[kp].y), first.depth[kp]);
        landmark[i] = map.add_landmark(first.T_cam_world.inverse() * p_cam, id);
      }
      map.keyframe(id)->landmarks[static_cast<std::size_t>(keypoint)] = landmark[i];
      map.add_observation(landmark[i], id, keypoint);
    }
    map.update_covisibility(id);
  }
  for (const rgbl::LandmarkId l : landmark) {
    if (l.valid()) map.update_landmark(l);
  }
  rgbl::LocalMappingOptions options;
  options.fusion = false;
  options.keyframe_culling = false;
  options.max_new_depth_points = 0;
  options.pairs.lidar_sigma_translation = 0.0;
  options.depth_consistency = depth_consistency;
  rgbl::LocalMapper mapper(map, s.camera, options);
  mapper.process(map.last_keyframe_id());
  mapper.process(map.last_keyframe_id());
  HedgeMapping out;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const rgbl::Landmark* l = landmark[i].valid() ? map.landmark(landmark[i]) : nullptr;
    if (l == nullptr || l->observations.size() < 3) continue;
    const double error = (l->position - s.points[i]).norm();
    const bool scaled = l->depth_sigma_scale > 1.0;
    if (near_hedge(i)) {
      out.hedge_error += error;
      ++out.hedge;
      out.hedge_scaled += scaled ? 1 : 0;
    } else if (!in_hedge(i)) {
      out.other_error += error;
      ++out.other;
      out.other_scaled += scaled ? 1 : 0;
    }
  }
  out.hedge_error /= std::max(out.hedge, 1);
  out.other_error /= std::max(out.other, 1);
  return out;
}

}  // namespace

TEST_CASE("local mapping weighs a hedge's depths by how far they disagree with its parallax") {
  const HedgeMapping off = map_hedge(false);
  const HedgeMapping on = map_hedge(true);
  REQUIRE(on.hedge >= 10);
  REQUIRE(on.other >= 100);
  INFO("hedge " << off.hedge_error << " -> " << on.hedge_error << " m, others " << off.other_error << " -> "
                << on.other_error << " m; scaled " << on.hedge_scaled << " of " << on.hedge << " and "
                << on.other_scaled << " of " << on.other);
  CHECK(off.hedge_scaled == 0);  // off: every sigma as measured
  // 0.2-0.4 m deep at 6-14 m against 0.05 m sigmas and 2 m of baseline: most of the hedge is caught
  CHECK(on.hedge_scaled >= 0.8 * on.hedge);
  CHECK(on.other_scaled <= 0.1 * on.other);
  // and its landmarks follow the images: nearer the truth than where the depths hold them
  CHECK(on.hedge_error < 0.6 * off.hedge_error);
  CHECK(on.other_error <= 1.1 * off.other_error);
}

namespace {

// Three keyframes 0.5 m apart over random points 6-14 m ahead; the first 30 points have depth and
// landmarks seen by all three (the covisibility), the rest neither, as far points without a return;
// every fifth of those the first keyframe does not recognise.
// Local mapping of the last keyframe with triangulation on, nothing else that adds or removes.
struct TriangulatedScene {
  rgbl::test::PointsMap scene;
  rgbl::Map map;
  rgbl::LocalMappingStats stats;
};

void map_with_triangulation(TriangulatedScene& t, int min_views) {
  constexpr std::size_t kWithDepth = 30;
  t.scene = rgbl::test::make_points_map(3, 150, 5);
  for (int k = 0; k < 3; ++k) {
    rgbl::Keyframe kf = rgbl::test::make_points_keyframe(t.scene, k, t.scene.T_cam_world[static_cast<std::size_t>(k)]);
    rgbl::test::drop_depth(t.scene, k, kWithDepth, kf);
    for (std::size_t i = kWithDepth; k == 0 && i < t.scene.points.size(); i += 5) {
      // every fifth point looks different to the first keyframe (64 bits away): two views only
      int& kp = t.scene.keypoint_of_point[0][i];
      if (kp < 0) continue;
      for (std::size_t byte = 0; byte < 8; ++byte) kf.descriptors[static_cast<std::size_t>(kp)][byte] ^= 0xFF;
      kp = -1;
    }
    t.map.add_keyframe(std::move(kf));
  }
  rgbl::test::add_shared_landmarks(t.scene, kWithDepth, t.map);
  rgbl::LocalMappingOptions options;
  options.triangulation = true;
  options.triangulation_min_views = min_views;
  options.max_new_depth_points = 0;
  options.local_ba = false;
  options.keyframe_culling = false;
  rgbl::LocalMapper mapper(t.map, t.scene.camera, options);
  t.stats = mapper.process(rgbl::KeyframeId{2});
}

}  // namespace

TEST_CASE("local mapping triangulates keypoints without depth and keeps what a third keyframe sees") {
  for (const int min_views : {3, 2}) {
    TriangulatedScene t;
    map_with_triangulation(t, min_views);
    const auto& seen = t.scene.keypoint_of_point;
    int in_all = 0, in_two = 0;
    for (std::size_t i = 30; i < t.scene.points.size(); ++i) {
      const int views = (seen[0][i] >= 0 ? 1 : 0) + (seen[1][i] >= 0 ? 1 : 0);
      if (seen[2][i] < 0 || views == 0) continue;
      ++(views == 2 ? in_all : in_two);
    }
    REQUIRE(in_all > 40);
    REQUIRE(in_two > 5);
    INFO("min_views " << min_views);
    CHECK(t.stats.triangulated_landmarks == (min_views == 3 ? in_all : in_all + in_two));
    // each new landmark sits on its point and is seen by every keyframe that sees that point
    int checked = 0;
    double worst = 0.0;
    for (std::size_t i = 30; i < t.scene.points.size(); ++i) {
      if (seen[2][i] < 0) continue;
      const rgbl::LandmarkId id = t.map.keyframe(rgbl::KeyframeId{2})->landmarks[static_cast<std::size_t>(seen[2][i])];
      if (!id.valid()) continue;
      const rgbl::Landmark& l = *t.map.landmark(id);
      for (int k = 0; k < 3; ++k) {
        const int kp = seen[static_cast<std::size_t>(k)][i];
        CHECK((kp >= 0 ? l.observations.count(rgbl::KeyframeId{k}) == 1 && l.observations.at(rgbl::KeyframeId{k}) == kp
                       : l.observations.count(rgbl::KeyframeId{k}) == 0));
      }
      worst = std::max(worst, (l.position - t.scene.points[i]).norm());
      ++checked;
    }
    CHECK(checked == t.stats.triangulated_landmarks);
    CHECK(worst < 1e-3);
  }
}
