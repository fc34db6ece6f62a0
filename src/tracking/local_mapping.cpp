#include "rgbl/tracking/local_mapping.hpp"

#include "matching.hpp"

#include "rgbl/backend/bundle_adjustment.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/tracking/frame.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <mutex>
#include <set>
#include <shared_mutex>

namespace rgbl {

LocalMapper::LocalMapper(Map& map, const PinholeCamera& camera, LocalMappingOptions options)
    : map_(map), camera_(camera), options_(options) {
  options_.validate();
}

LocalMappingStats LocalMapper::process(KeyframeId keyframe) {
  LocalMappingStats stats;
  abort_ = false;
  {
    std::unique_lock lock(map_.mutex());
    associate(keyframe);
    stats.culled_landmarks = cull_landmarks(keyframe);
    stats.new_landmarks = create_depth_landmarks(keyframe);
    if (options_.fusion) stats.fused_landmarks = fuse(keyframe);
  }
  if (options_.local_ba) stats.ba_outliers = local_bundle_adjustment(keyframe, stats.ba_ms);
  if (options_.keyframe_culling) {
    std::unique_lock lock(map_.mutex());
    stats.culled_keyframes = cull_keyframes(keyframe);
  }
  return stats;
}

void LocalMapper::associate(KeyframeId id) {
  Keyframe* kf = map_.keyframe(id);
  if (kf == nullptr) return;
  for (const LandmarkId l : kf->landmarks) {
    if (l.valid()) map_.update_landmark(l);
  }
  map_.update_covisibility(id);
}

int LocalMapper::cull_landmarks(KeyframeId current) {
  int culled = 0;
  std::vector<LandmarkId> keep;
  for (const LandmarkId id : recent_landmarks_) {
    const Landmark* l = map_.landmark(id);
    if (l == nullptr) continue;
    const int age = current.value - l->first_keyframe.value;
    if (l->found_ratio() < options_.min_found_ratio ||
        (age >= 2 && static_cast<int>(l->observations.size()) < options_.min_observations)) {
      map_.erase_landmark(id);
      ++culled;
    } else if (age < 3) {
      keep.push_back(id);
    }
  }
  recent_landmarks_ = std::move(keep);
  return culled;
}

int LocalMapper::create_depth_landmarks(KeyframeId id) {
  Keyframe* kf = map_.keyframe(id);
  if (kf == nullptr) return 0;
  std::vector<std::pair<float, std::size_t>> candidates;
  for (std::size_t i = 0; i < kf->keypoints.size(); ++i) {
    if (kf->depth_sigma[i] > 0.0F && !kf->landmarks[i].valid()) candidates.emplace_back(kf->depth[i], i);
  }
  std::sort(candidates.begin(), candidates.end());
  const Eigen::Isometry3d T_world_cam = kf->T_cam_world.inverse();
  int created = 0;
  for (const auto& [z, i] : candidates) {
    if (created >= options_.max_new_depth_points) break;
    const Eigen::Vector3d p = camera_.unproject(Eigen::Vector2d(kf->keypoints[i].x, kf->keypoints[i].y), z);
    const LandmarkId l = map_.add_landmark(T_world_cam * p, id);
    map_.add_observation(l, id, static_cast<int>(i));
    map_.update_landmark(l);
    recent_landmarks_.push_back(l);
    ++created;
    kf = map_.keyframe(id);
  }
  return created;
}

int LocalMapper::fuse_into(KeyframeId target_id, const std::vector<LandmarkId>& landmarks) {
  const Keyframe* target = map_.keyframe(target_id);
  if (target == nullptr) return 0;
  const FeatureGrid grid(target->keypoints, camera_.width, camera_.height);
  const Eigen::Vector3d center = target->center();
  const double scale = map_.options().scale_factor;
  const int levels = map_.options().levels;
  std::vector<int> cell;
  int fused = 0;
  for (const LandmarkId id : landmarks) {
    const Landmark* l = map_.landmark(id);
    target = map_.keyframe(target_id);
    if (l == nullptr || target == nullptr || l->observations.count(target_id) != 0) continue;
    const Eigen::Vector3d p = target->T_cam_world * l->position;
    if (p.z() <= 0.0) continue;
    const Eigen::Vector2d px = camera_.project_unchecked(p);
    if (!camera_.in_image(px)) continue;
    const Eigen::Vector3d ray = l->position - center;
    const double distance = ray.norm();
    if (distance < 0.8 * l->min_distance || distance > 1.2 * l->max_distance) continue;
    if (ray.dot(l->normal) < 0.5 * distance) continue;
    const int level = l->predict_level(distance, levels, scale);
    const double radius = options_.fusion_radius * std::pow(scale, level);
    grid.query(static_cast<float>(px.x()), static_cast<float>(px.y()), static_cast<float>(radius),
               std::max(0, level - 1), level, cell);
    int best = INT_MAX, best_index = -1;
    for (const int k : cell) {
      const auto ks = static_cast<std::size_t>(k);
      const Keypoint& kp = target->keypoints[ks];
      const double sigma = std::pow(scale, kp.level);
      double chi2 = (Eigen::Vector2d(kp.x, kp.y) - px).squaredNorm() / (sigma * sigma);
      double threshold = 5.991;
      if (target->depth_sigma[ks] > 0.0F) {
        const double dz = (p.z() - target->depth[ks]) / target->depth_sigma[ks];
        chi2 += dz * dz;
        threshold = 7.815;
      }
      if (chi2 > threshold) continue;
      const int d = hamming_distance(l->descriptor, target->descriptors[ks]);
      if (d < best) {
        best = d;
        best_index = k;
      }
    }
    if (best_index < 0 || best > 50) continue;
    const LandmarkId existing = target->landmarks[static_cast<std::size_t>(best_index)];
    if (existing.valid()) {
      const Landmark* e = map_.landmark(existing);
      if (e == nullptr) continue;
      // Keep the landmark with more observations.
      if (e->observations.size() > l->observations.size()) map_.replace_landmark(id, existing);
      else map_.replace_landmark(existing, id);
    } else {
      map_.add_observation(id, target_id, best_index);
    }
    ++fused;
  }
  return fused;
}

int LocalMapper::fuse(KeyframeId id) {
  std::vector<KeyframeId> targets = map_.best_covisible(id, static_cast<std::size_t>(options_.covisible_for_fusion));
  const std::size_t direct = targets.size();
  for (std::size_t i = 0; i < direct; ++i) {
    for (const KeyframeId second : map_.best_covisible(targets[i], 5)) {
      if (second != id && std::find(targets.begin(), targets.end(), second) == targets.end()) targets.push_back(second);
    }
  }
  int fused = 0;
  {
    const Keyframe* kf = map_.keyframe(id);
    if (kf == nullptr) return 0;
    std::vector<LandmarkId> own;
    for (const LandmarkId l : kf->landmarks) {
      if (l.valid()) own.push_back(l);
    }
    for (const KeyframeId t : targets) fused += fuse_into(t, own);
  }
  fused += fuse_into(id, map_.landmarks_seen_by(targets));
  if (const Keyframe* kf = map_.keyframe(id)) {
    for (const LandmarkId l : kf->landmarks) {
      if (l.valid()) map_.update_landmark(l);
    }
  }
  map_.update_covisibility(id);
  for (const KeyframeId t : targets) map_.update_covisibility(t);
  return fused;
}

int LocalMapper::local_bundle_adjustment(KeyframeId id, double& elapsed_ms) {
  Stopwatch watch;
  BundleProblem problem;
  std::vector<KeyframeId> pose_ids;
  std::vector<LandmarkId> point_ids;
  std::vector<std::pair<LandmarkId, KeyframeId>> observation_ids;
  {
    std::shared_lock lock(map_.mutex());
    if (map_.keyframe(id) == nullptr) return 0;
    std::vector<KeyframeId> local = {id};
    for (const KeyframeId k : map_.best_covisible(id, static_cast<std::size_t>(options_.max_local_ba_keyframes - 1))) {
      local.push_back(k);
    }
    std::map<KeyframeId, int> pose_index;
    for (const KeyframeId k : local) {
      pose_index[k] = static_cast<int>(problem.poses.size());
      problem.poses.push_back({map_.keyframe(k)->T_cam_world, k.value == 0});
      pose_ids.push_back(k);
    }
    std::set<LandmarkId> points;
    for (const KeyframeId k : local) {
      for (const LandmarkId l : map_.keyframe(k)->landmarks) {
        if (l.valid()) points.insert(l);
      }
    }
    // Fixed keyframes: those outside the window that see the most local landmarks.
    std::map<KeyframeId, int> outside;
    for (const LandmarkId l : points) {
      for (const auto& [k, index] : map_.landmark(l)->observations) {
        if (pose_index.count(k) == 0) ++outside[k];
      }
    }
    std::vector<std::pair<int, KeyframeId>> fixed_sorted;
    for (const auto& [k, n] : outside) fixed_sorted.emplace_back(n, k);
    std::sort(fixed_sorted.begin(), fixed_sorted.end(),
              [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
    for (std::size_t i = 0; i < fixed_sorted.size() && static_cast<int>(i) < options_.max_fixed_keyframes; ++i) {
      const KeyframeId k = fixed_sorted[i].second;
      pose_index[k] = static_cast<int>(problem.poses.size());
      problem.poses.push_back({map_.keyframe(k)->T_cam_world, true});
      pose_ids.push_back(k);
    }
    // Gauge: without a fixed keyframe, hold the oldest one.
    if (std::none_of(problem.poses.begin(), problem.poses.end(), [](const BundlePose& p) { return p.fixed; })) {
      std::size_t oldest = 0;
      for (std::size_t i = 1; i < pose_ids.size(); ++i) {
        if (pose_ids[i] < pose_ids[oldest]) oldest = i;
      }
      problem.poses[oldest].fixed = true;
    }
    const double scale = map_.options().scale_factor;
    for (const LandmarkId l : points) {
      const Landmark* landmark = map_.landmark(l);
      const int point = static_cast<int>(problem.points.size());
      problem.points.push_back(landmark->position);
      point_ids.push_back(l);
      for (const auto& [k, index] : landmark->observations) {
        const auto it = pose_index.find(k);
        if (it == pose_index.end()) continue;
        const Keyframe* kf = map_.keyframe(k);
        const auto ks = static_cast<std::size_t>(index);
        BundleObservation o;
        o.pose = it->second;
        o.point = point;
        o.pixel = Eigen::Vector2d(kf->keypoints[ks].x, kf->keypoints[ks].y);
        o.sigma_px = std::pow(scale, kf->keypoints[ks].level);
        if (kf->depth_sigma[ks] > 0.0F) {
          o.depth = kf->depth[ks];
          o.depth_sigma = kf->depth_sigma[ks];
        }
        problem.observations.push_back(o);
        observation_ids.emplace_back(l, k);
      }
    }
  }
  const BundleAdjustmentResult result = bundle_adjust(camera_, problem, options_.ba, &abort_);
  int outliers = 0;
  {
    std::unique_lock lock(map_.mutex());
    for (std::size_t i = 0; i < observation_ids.size(); ++i) {
      if (!result.outlier[i]) continue;
      map_.erase_observation(observation_ids[i].first, observation_ids[i].second);
      ++outliers;
    }
    for (std::size_t i = 0; i < pose_ids.size(); ++i) {
      if (problem.poses[i].fixed) continue;
      if (Keyframe* kf = map_.keyframe(pose_ids[i])) kf->T_cam_world = problem.poses[i].T_cam_world;
    }
    for (std::size_t i = 0; i < point_ids.size(); ++i) {
      if (Landmark* l = map_.landmark(point_ids[i])) {
        l->position = problem.points[i];
        map_.update_landmark(point_ids[i]);
      }
    }
    if (outliers > 0) {
      for (const KeyframeId k : pose_ids) map_.update_covisibility(k);
    }
  }
  elapsed_ms = watch.elapsed_ms();
  return outliers;
}

int LocalMapper::cull_keyframes(KeyframeId id) {
  int culled = 0;
  const double scale = map_.options().scale_factor;
  (void)scale;
  for (const KeyframeId k : map_.best_covisible(id, 100)) {
    if (k.value == 0 || k == id) continue;
    const Keyframe* kf = map_.keyframe(k);
    if (kf == nullptr) continue;
    int total = 0, redundant = 0;
    for (std::size_t i = 0; i < kf->landmarks.size(); ++i) {
      const Landmark* l = kf->landmarks[i].valid() ? map_.landmark(kf->landmarks[i]) : nullptr;
      if (l == nullptr || kf->depth_sigma[i] <= 0.0F) continue;
      ++total;
      if (static_cast<int>(l->observations.size()) <= options_.redundant_observers) continue;
      const int level = kf->keypoints[i].level;
      int observers = 0;
      for (const auto& [other, index] : l->observations) {
        if (other == k) continue;
        const Keyframe* o = map_.keyframe(other);
        if (o != nullptr && o->keypoints[static_cast<std::size_t>(index)].level <= level + 1) ++observers;
        if (observers >= options_.redundant_observers) break;
      }
      if (observers >= options_.redundant_observers) ++redundant;
    }
    if (total > 0 && redundant > options_.redundant_ratio * total) {
      map_.erase_keyframe(k);
      ++culled;
    }
  }
  return culled;
}

}  // namespace rgbl
