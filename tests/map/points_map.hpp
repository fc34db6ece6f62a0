#pragma once
// A map with exactly known geometry for fusion and bundle adjustment tests: points in front of a
// row of keyframes, each keyframe with one keypoint per visible point at its exact projection, exact
// depth, and one random descriptor per point shared by all its keypoints.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/map/map.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <vector>

namespace rgbl::test {

struct PointsMap {
  PinholeCamera camera{.fx = 500.0, .fy = 500.0, .cx = 320.0, .cy = 240.0, .width = 640, .height = 480};
  std::vector<Eigen::Vector3d> points;               // world
  std::vector<Descriptor> descriptors;               // per point
  std::vector<Eigen::Isometry3d> T_cam_world;        // per keyframe, the truth
  std::vector<std::vector<int>> keypoint_of_point;   // per keyframe, per point: keypoint index or -1
};

// `keyframes` cameras 0.5 m apart along x looking along +z, `count` points 6-14 m ahead.
inline PointsMap make_points_map(int keyframes, int count, std::uint32_t seed = 7) {
  PointsMap s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> lateral(-3.0, 3.0), ahead(6.0, 14.0);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < count; ++i) {
    s.points.emplace_back(lateral(rng), 0.6 * lateral(rng), ahead(rng));
    Descriptor d{};
    for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
    s.descriptors.push_back(d);
  }
  for (int k = 0; k < keyframes; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(-0.5 * k, 0.0, 0.0);  // camera centre at x = 0.5 k
    s.T_cam_world.push_back(T);
  }
  return s;
}

// The keyframe k of the scene (keypoints, descriptors, depth; no landmarks), at pose T_cam_world.
inline Keyframe make_points_keyframe(PointsMap& s, int k, const Eigen::Isometry3d& T_cam_world) {
  Keyframe kf;
  kf.T_cam_world = T_cam_world;
  kf.frame_index = static_cast<std::size_t>(k);
  std::vector<int> index(s.points.size(), -1);
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const Eigen::Vector3d p = s.T_cam_world[static_cast<std::size_t>(k)] * s.points[i];
    const auto px = s.camera.project(p);
    if (!px) continue;
    index[i] = static_cast<int>(kf.keypoints.size());
    Keypoint kp;
    kp.x = static_cast<float>(px->x());
    kp.y = static_cast<float>(px->y());
    kf.keypoints.push_back(kp);
    kf.descriptors.push_back(s.descriptors[i]);
    kf.depth.push_back(static_cast<float>(p.z()));
    kf.depth_sigma.push_back(0.05F);
    kf.landmarks.emplace_back();
  }
  s.keypoint_of_point.push_back(std::move(index));
  return kf;
}

// Keyframe k's keypoints of the points from `first` on lose their depth, as far points without a
// LiDAR return.
inline void drop_depth(const PointsMap& s, int k, std::size_t first, Keyframe& kf) {
  for (std::size_t i = first; i < s.points.size(); ++i) {
    const int kp = s.keypoint_of_point[static_cast<std::size_t>(k)][i];
    if (kp < 0) continue;
    kf.depth[static_cast<std::size_t>(kp)] = 0.0F;
    kf.depth_sigma[static_cast<std::size_t>(kp)] = 0.0F;
  }
}

// A landmark at each of the first `count` points, observed by every keyframe of the map that sees it
// (the map's keyframes are the scene's, in order), and the covisibility that gives.
inline void add_shared_landmarks(const PointsMap& s, std::size_t count, Map& map) {
  const std::size_t keyframes = s.keypoint_of_point.size();
  for (std::size_t i = 0; i < count; ++i) {
    const LandmarkId l = map.add_landmark(s.points[i], KeyframeId{0});
    for (std::size_t k = 0; k < keyframes; ++k) {
      const int kp = s.keypoint_of_point[k][i];
      if (kp >= 0) map.add_observation(l, KeyframeId{static_cast<int>(k)}, kp);
    }
    map.update_landmark(l);
  }
  for (std::size_t k = 0; k < keyframes; ++k) map.update_covisibility(KeyframeId{static_cast<int>(k)});
}

}  // namespace rgbl::test
