#include "rgbl/backend/map_bundle.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <set>

namespace rgbl {

MapBundle make_map_bundle(const Map& map, std::span<const KeyframeId> window, std::span<const KeyframeId> anchors,
                          KeyframeId held) {
  MapBundle bundle;
  std::map<KeyframeId, int> pose_index;
  const auto add_pose = [&](KeyframeId k, bool fixed) {
    const Keyframe* kf = map.keyframe(k);
    if (kf == nullptr || pose_index.count(k) != 0) return;
    pose_index[k] = static_cast<int>(bundle.problem.poses.size());
    bundle.problem.poses.push_back({kf->T_cam_world, fixed});
    bundle.keyframes.push_back(k);
  };
  for (const KeyframeId k : window) add_pose(k, k == held);
  const std::size_t window_poses = bundle.keyframes.size();
  for (const KeyframeId k : anchors) add_pose(k, true);

  std::set<LandmarkId> points;
  for (std::size_t i = 0; i < window_poses; ++i) {
    for (const LandmarkId l : map.keyframe(bundle.keyframes[i])->landmarks) {
      if (l.valid()) points.insert(l);
    }
  }
  const double scale = map.options().scale_factor;
  for (const LandmarkId l : points) {
    const Landmark* landmark = map.landmark(l);
    const int point = static_cast<int>(bundle.problem.points.size());
    bundle.problem.points.push_back(landmark->position);
    bundle.landmarks.push_back(l);
    for (const auto& [k, index] : landmark->observations) {
      const auto it = pose_index.find(k);
      if (it == pose_index.end()) continue;
      const Keyframe* kf = map.keyframe(k);
      const auto ks = static_cast<std::size_t>(index);
      BundleObservation o;
      o.pose = it->second;
      o.point = point;
      o.pixel = Eigen::Vector2d(kf->keypoints[ks].x, kf->keypoints[ks].y);
      o.sigma_px = std::pow(scale, kf->keypoints[ks].level);
      if (kf->depth_sigma[ks] > 0.0F) {
        o.depth = kf->depth[ks];
        o.depth_sigma = kf->depth_sigma[ks] * landmark->depth_sigma_scale;
      }
      bundle.problem.observations.push_back(o);
      bundle.observations.emplace_back(l, k);
    }
  }
  return bundle;
}

void KeyframePairOptions::validate() const {
  require(std::isfinite(road_sigma_offset) && road_sigma_offset >= 0.0, "keyframe_pairs.road_sigma_offset",
          ">= 0 m (0 = off)");
  require(std::isfinite(road_sigma_tilt_deg) && road_sigma_tilt_deg >= 0.0, "keyframe_pairs.road_sigma_tilt_deg",
          ">= 0 deg (0 = off)");
  require(std::isfinite(road_max_distance) && road_max_distance > 0.0, "keyframe_pairs.road_max_distance", "> 0 m");
  require(std::isfinite(odometry_sigma_translation) && odometry_sigma_translation >= 0.0,
          "keyframe_pairs.odometry_sigma_translation", ">= 0 m (0 = off)");
  require(std::isfinite(odometry_sigma_rotation) && odometry_sigma_rotation >= 0.0,
          "keyframe_pairs.odometry_sigma_rotation", ">= 0 rad (0 = off)");
  require(std::isfinite(lidar_sigma_translation) && lidar_sigma_translation >= 0.0,
          "keyframe_pairs.lidar_sigma_translation", ">= 0 m (0 = off)");
  require(std::isfinite(lidar_sigma_rotation) && lidar_sigma_rotation > 0.0, "keyframe_pairs.lidar_sigma_rotation",
          "> 0 rad");
  require(std::isfinite(lidar_agreeing_sigma_translation) && lidar_agreeing_sigma_translation >= 0.0,
          "keyframe_pairs.lidar_agreeing_sigma_translation", ">= 0 m (0 = lidar_sigma_translation)");
}

void add_keyframe_pairs(const Map& map, MapBundle& bundle, const KeyframePairOptions& options) {
  const auto& poses = bundle.problem.poses;
  if (options.road_sigma_offset > 0.0 && options.road_sigma_tilt_deg > 0.0) {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const Keyframe* kf = map.keyframe(bundle.keyframes[i]);
      if (poses[i].fixed || kf == nullptr || !kf->road) continue;
      std::optional<std::size_t> older;
      for (std::size_t j = 0; j < poses.size(); ++j) {
        const Keyframe* other = map.keyframe(bundle.keyframes[j]);
        if (j == i || other == nullptr || !other->road || !(bundle.keyframes[j] < bundle.keyframes[i])) continue;
        if ((other->center() - kf->center()).norm() > options.road_max_distance) continue;
        if (!older || bundle.keyframes[*older] < bundle.keyframes[j]) older = j;
      }
      if (!older) continue;
      BundlePlanePair pair;
      pair.pose_a = static_cast<int>(*older);
      pair.pose_b = static_cast<int>(i);
      pair.plane_a = *map.keyframe(bundle.keyframes[*older])->road;
      pair.plane_b = *kf->road;
      pair.sigma_offset = options.road_sigma_offset;
      pair.sigma_tilt = options.road_sigma_tilt_deg * std::numbers::pi / 180.0;
      bundle.problem.plane_pairs.push_back(pair);
    }
  }
  // Each optimised keyframe whose previous keyframe is in the problem: the keyframe and the two poses.
  const auto for_each_with_previous = [&](auto&& add) {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const Keyframe* kf = map.keyframe(bundle.keyframes[i]);
      if (poses[i].fixed || kf == nullptr || !kf->previous.valid()) continue;
      const auto previous = std::find(bundle.keyframes.begin(), bundle.keyframes.end(), kf->previous);
      if (previous != bundle.keyframes.end()) add(*kf, static_cast<int>(previous - bundle.keyframes.begin()), static_cast<int>(i));
    }
  };
  if (options.odometry_sigma_translation > 0.0 && options.odometry_sigma_rotation > 0.0) {
    for_each_with_previous([&](const Keyframe& kf, int a, int b) {
      bundle.problem.pose_pairs.push_back({.pose_a = a, .pose_b = b, .T_b_a = kf.T_cam_previous,
                                           .sigma_translation = options.odometry_sigma_translation,
                                           .sigma_rotation = options.odometry_sigma_rotation,
                                           // a truck beside the car lifted tracked steps by 0.2-0.3 m; the
                                           // road planes agree within 0.05 m
                                           .level_only = kf.road && map.keyframe(kf.previous)->road});
    });
  }
  if (options.lidar_sigma_translation > 0.0) {
    for_each_with_previous([&](const Keyframe& kf, int a, int b) {
      if (!kf.T_cam_previous_lidar) return;
      const Eigen::Isometry3d change = *kf.T_cam_previous_lidar * kf.T_cam_previous.inverse();
      const bool agreeing = options.lidar_agreeing_sigma_translation > 0.0 &&
                            change.translation().norm() <= options.odometry_sigma_translation &&
                            rotation_angle(change.linear()) <= options.odometry_sigma_rotation;
      bundle.problem.pose_pairs.push_back({.pose_a = a, .pose_b = b, .T_b_a = *kf.T_cam_previous_lidar,
                                           .sigma_translation = agreeing ? options.lidar_agreeing_sigma_translation
                                                                         : options.lidar_sigma_translation,
                                           .sigma_rotation = options.lidar_sigma_rotation});
    });
  }
}

int apply_map_bundle(Map& map, const MapBundle& bundle, const BundleAdjustmentResult& result) {
  int outliers = 0;
  for (std::size_t i = 0; i < bundle.observations.size() && i < result.outlier.size(); ++i) {
    if (!result.outlier[i]) continue;
    map.erase_observation(bundle.observations[i].first, bundle.observations[i].second);
    ++outliers;
  }
  for (std::size_t i = 0; i < bundle.keyframes.size(); ++i) {
    if (bundle.problem.poses[i].fixed) continue;
    if (Keyframe* kf = map.keyframe(bundle.keyframes[i])) kf->T_cam_world = bundle.problem.poses[i].T_cam_world;
  }
  for (std::size_t i = 0; i < bundle.landmarks.size(); ++i) {
    if (Landmark* l = map.landmark(bundle.landmarks[i])) {
      l->position = bundle.problem.points[i];
      map.update_landmark(bundle.landmarks[i]);
    }
  }
  if (outliers > 0) {
    for (const KeyframeId k : bundle.keyframes) map.update_covisibility(k);
  }
  return outliers;
}

}  // namespace rgbl
