#include "rgbl/tracking/local_mapping.hpp"

#include "rgbl/backend/map_bundle.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/map/depth_consistency.hpp"
#include "rgbl/map/fusion.hpp"
#include "rgbl/map/triangulation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <mutex>
#include <map>
#include <shared_mutex>
#include <utility>

namespace rgbl {

LocalMapper::LocalMapper(Map& map, const PinholeCamera& camera, LocalMappingOptions options)
    : map_(map), camera_(camera), options_(options) {
  options_.validate();
}

LocalMappingStats LocalMapper::process(KeyframeId keyframe, const std::vector<LandmarkId>& created_with_keyframe) {
  LocalMappingStats stats;
  abort_ = false;
  {
    std::unique_lock lock(map_.mutex());
    associate(keyframe);
    stats.culled_landmarks = cull_landmarks(keyframe);
    for (const LandmarkId l : created_with_keyframe) {
      if (map_.landmark(l) != nullptr) recent_landmarks_.push_back({l, false});
    }
    const int budget = options_.max_new_depth_points - static_cast<int>(created_with_keyframe.size());
    const std::vector<LandmarkId> created = create_depth_landmarks(map_, camera_, keyframe, std::max(budget, 0));
    for (const LandmarkId l : created) recent_landmarks_.push_back({l, false});
    stats.new_landmarks = static_cast<int>(created_with_keyframe.size() + created.size());
    std::vector<LandmarkId> triangulated;
    if (options_.triangulation) {
      Stopwatch watch;
      triangulated = triangulate_landmarks(map_, camera_, keyframe, options_.triangulation_match);
      for (const LandmarkId l : triangulated) recent_landmarks_.push_back({l, false});
      stats.triangulated_landmarks = static_cast<int>(triangulated.size());
      logger()->debug("keyframe {}: {} landmarks triangulated ({:.1f} ms)", keyframe.value, triangulated.size(),
                      watch.elapsed_ms());
    }
    if (options_.fusion) stats.fused_landmarks = fuse(keyframe);
    if (options_.triangulation && options_.triangulation_min_views > 2) {
      // two views agree on any pair along an epipolar line through repeated texture; a third view at
      // the predicted place (found by the fusion just run) is what tells a point from a coincidence
      int unconfirmed = 0;
      for (const LandmarkId l : triangulated) {
        const Landmark* landmark = map_.landmark(l);
        if (landmark != nullptr && std::cmp_less(landmark->observations.size(), options_.triangulation_min_views)) {
          map_.erase_landmark(l);
          ++unconfirmed;
        }
      }
      stats.triangulated_landmarks -= unconfirmed;
      logger()->debug("keyframe {}: {} triangulated landmarks not seen in a third keyframe", keyframe.value, unconfirmed);
    }
  }
  if (options_.pairs.lidar_sigma_translation > 0.0) {
    measure_lidar_pair(keyframe);
  } else {
    std::unique_lock lock(map_.mutex());
    if (Keyframe* kf = map_.keyframe(keyframe)) kf->scan.reset();
  }
  if (options_.local_ba) stats.ba_outliers = local_bundle_adjustment(keyframe, stats.ba_ms);
  if (options_.keyframe_culling) {
    std::unique_lock lock(map_.mutex());
    stats.culled_keyframes = cull_keyframes(keyframe);
    if (options_.place_culling) {
      stats.culled_revisited = cull_revisited(keyframe);
      stats.culled_keyframes += stats.culled_revisited;
    }
  }
  return stats;
}


void LocalMapper::measure_lidar_pair(KeyframeId id) {
  std::shared_ptr<const ScanSample> scan, previous_scan;
  Eigen::Isometry3d T_cam_previous = Eigen::Isometry3d::Identity();
  std::size_t frame = 0, previous_frame = 0;  // for the log
  {
    // A keyframe's scan is needed until the next keyframe is registered onto it, no longer: the
    // previous one's is handed over here (a KITTI sample: ~14 000 points of 12 bytes; thousands of keyframes on a long
    // drive). Erasing a keyframe composes the measured motions, it does not register again.
    std::unique_lock lock(map_.mutex());
    Keyframe* kf = map_.keyframe(id);
    Keyframe* previous = kf != nullptr && kf->previous.valid() ? map_.keyframe(kf->previous) : nullptr;
    if (previous == nullptr) return;
    previous_scan = std::move(previous->scan);  // leaves it null
    if (!kf->scan || !previous_scan) return;
    scan = kf->scan;
    T_cam_previous = kf->T_cam_previous;
    frame = kf->frame_index;
    previous_frame = previous->frame_index;
  }
  // both samples are in their camera frames: the registration is between the cameras
  Stopwatch watch;
  const std::vector<LidarPoint> reference = as_points(*previous_scan), query = as_points(*scan);
  const auto r = register_scans(reference, query, T_cam_previous.inverse(), options_.lidar_registration);
  const double ms = watch.elapsed_ms();
  if (!r) {
    logger()->debug("keyframe {}: LiDAR pair not kept (too little to register)", id.value);
    return;
  }
  const Eigen::Isometry3d measured = r->T_reference_query.inverse();
  const Eigen::Isometry3d change = measured * T_cam_previous.inverse();
  const double change_deg = rotation_angle(change.linear()) * 180.0 / std::numbers::pi;
  const char* refused = !r->converged                                         ? "not converged"
                        : r->min_probe_loss <= options_.lidar_min_probe_loss ? "not pinned down"
                        : change.translation().norm() > options_.lidar_max_change_m ||
                                change_deg > options_.lidar_max_change_deg
                            ? "too far from the tracked step"
                            : nullptr;
  if (logger()->should_log(spdlog::level::debug)) {
    // the registered motion in full, for scripts/lidar_pairs.py to compare with a ground truth
    const Eigen::Vector3d t = measured.translation(), w = so3_log(measured.linear());
    logger()->debug("keyframe {}: LiDAR pair {}{} ({:.3f} m, {:.3f} deg from the tracked step of {:.3f} m; its own {:.3f} m; "
                    "probe loss {:.4f}, landing {:.3f}; {} and {} points, {:.1f} ms; frames {} -> {}, T_cam_previous t {:.5f} {:.5f} "
                    "{:.5f} rad {:.6f} {:.6f} {:.6f})",
                    id.value, refused != nullptr ? "not kept: " : "kept", refused != nullptr ? refused : "",
                    change.translation().norm(), change_deg, T_cam_previous.translation().norm(),
                    measured.translation().norm(), r->min_probe_loss, r->agreement, reference.size(), query.size(), ms,
                    previous_frame, frame, t.x(), t.y(), t.z(), w.x(), w.y(), w.z());
  }
  if (refused != nullptr) return;
  std::unique_lock lock(map_.mutex());
  // the previous keyframe may have been erased meanwhile (its motion handed on): then this is stale
  if (Keyframe* kf = map_.keyframe(id); kf != nullptr && kf->T_cam_previous.isApprox(T_cam_previous)) {
    kf->T_cam_previous_lidar = measured;
  }
}

void LocalMapper::watch_initial(KeyframeId id) {
  std::shared_lock lock(map_.mutex());
  const Keyframe* kf = map_.keyframe(id);
  if (kf == nullptr) return;
  for (const LandmarkId l : kf->landmarks) {
    if (l.valid()) recent_landmarks_.push_back({l, true});
  }
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
  std::vector<WatchedLandmark> keep;
  for (const WatchedLandmark& w : recent_landmarks_) {
    const Landmark* l = map_.landmark(w.id);
    if (l == nullptr) continue;
    const int age = current.value - l->first_keyframe.value;
    if (l->found_ratio() < options_.min_found_ratio ||
        (!w.initial && age >= 2 && static_cast<int>(l->observations.size()) < options_.min_observations)) {
      map_.erase_landmark(w.id);
      ++culled;
    } else if (age < 3) {
      keep.push_back(w);
    }
  }
  recent_landmarks_ = std::move(keep);
  return culled;
}

std::vector<LandmarkId> create_depth_landmarks(Map& map, const PinholeCamera& camera, KeyframeId id, int max_points) {
  std::vector<LandmarkId> created;
  const Keyframe* kf = map.keyframe(id);
  if (kf == nullptr) return created;
  std::vector<std::pair<float, std::size_t>> candidates;
  for (std::size_t i = 0; i < kf->keypoints.size(); ++i) {
    if (kf->depth_sigma[i] > 0.0F && !kf->landmarks[i].valid()) candidates.emplace_back(kf->depth[i], i);
  }
  std::sort(candidates.begin(), candidates.end());
  const Eigen::Isometry3d T_world_cam = kf->T_cam_world.inverse();
  for (const auto& [z, i] : candidates) {
    if (static_cast<int>(created.size()) >= max_points) break;
    const Eigen::Vector3d p = camera.unproject(Eigen::Vector2d(kf->keypoints[i].x, kf->keypoints[i].y), z);
    const LandmarkId l = map.add_landmark(T_world_cam * p, id);
    map.add_observation(l, id, static_cast<int>(i));
    map.update_landmark(l);
    created.push_back(l);
    kf = map.keyframe(id);
  }
  return created;
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
    for (const KeyframeId t : targets) fused += fuse_landmarks(map_, camera_, t, own, options_.fusion_match);
  }
  fused += fuse_landmarks(map_, camera_, id, map_.landmarks_seen_by(targets), options_.fusion_match);
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
  MapBundle bundle;
  {
    std::shared_lock lock(map_.mutex());
    if (map_.keyframe(id) == nullptr) return 0;
    const std::vector<KeyframeId> local =
        map_.neighbourhood(id, static_cast<std::size_t>(options_.max_local_ba_keyframes - 1));
    // Fixed keyframes: those outside the window that see the most local landmarks.
    std::map<KeyframeId, int> outside;
    for (const LandmarkId l : map_.landmarks_seen_by(local)) {
      for (const auto& [k, index] : map_.landmark(l)->observations) {
        if (std::find(local.begin(), local.end(), k) == local.end()) ++outside[k];
      }
    }
    std::vector<std::pair<int, KeyframeId>> fixed_sorted;
    for (const auto& [k, n] : outside) fixed_sorted.emplace_back(n, k);
    std::sort(fixed_sorted.begin(), fixed_sorted.end(),
              [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
    std::vector<KeyframeId> anchors;
    for (std::size_t i = 0; i < fixed_sorted.size() && std::cmp_less(i, options_.max_fixed_keyframes); ++i) {
      anchors.push_back(fixed_sorted[i].second);
    }
    bundle = make_map_bundle(map_, local, anchors, KeyframeId{0});
    // Gauge: without a fixed keyframe, hold the oldest one.
    auto& poses = bundle.problem.poses;
    if (std::none_of(poses.begin(), poses.end(), [](const BundlePose& p) { return p.fixed; })) {
      const auto oldest = std::min_element(bundle.keyframes.begin(), bundle.keyframes.end());
      poses[static_cast<std::size_t>(oldest - bundle.keyframes.begin())].fixed = true;
    }
    add_keyframe_pairs(map_, bundle, options_.pairs);
  }
  const BundleAdjustmentResult result = bundle_adjust(camera_, bundle.problem, options_.ba, &abort_);
  int outliers = 0;
  {
    std::unique_lock lock(map_.mutex());
    outliers = apply_map_bundle(map_, bundle, result);
    if (options_.depth_consistency) {
      int scaled = 0;
      for (const LandmarkId adjusted : bundle.landmarks) {
        if (Landmark* l = map_.landmark(adjusted)) {
          l->depth_sigma_scale = depth_consistency_scale(map_, *l, camera_);
          scaled += l->depth_sigma_scale > 1.0 ? 1 : 0;
        }
      }
      logger()->debug("keyframe {}: {} of {} landmarks' depths disagree with their parallax", id.value, scaled,
                      bundle.landmarks.size());
    }
  }
  elapsed_ms = watch.elapsed_ms();
  return outliers;
}

int LocalMapper::cull_keyframes(KeyframeId id) {
  int culled = 0;
  for (const KeyframeId k : map_.best_covisible(id, 100)) {
    if (k.value == 0 || k == id) continue;
    const Keyframe* kf = map_.keyframe(k);
    // a map's root stays: frames of a map started after a loss hang from it, and move with it when
    // that map is merged into another
    if (kf == nullptr || !kf->parent.valid()) continue;
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

int LocalMapper::cull_revisited(KeyframeId id) {
  const Keyframe* current = map_.keyframe(id);
  if (current == nullptr) return 0;
  const double median_depth = current->median_depth();
  if (median_depth <= 0.0) return 0;
  const double radius = options_.place_distance_ratio * median_depth;
  const double min_cos = std::cos(options_.place_angle_deg * std::numbers::pi / 180.0);
  const Eigen::Vector3d centre = current->center();
  const Eigen::Vector3d axis = current->T_cam_world.linear().row(2).transpose();  // optical axis in the world
  std::vector<KeyframeId> same_place;
  for (const KeyframeId k : map_.best_covisible(id, 100)) {
    const Keyframe* kf = map_.keyframe(k);
    if (kf == nullptr || k.value >= id.value) continue;
    if ((kf->center() - centre).norm() > radius) continue;
    if (kf->T_cam_world.linear().row(2).transpose().dot(axis) < min_cos) continue;
    same_place.push_back(k);
  }
  // A revisit, not the keyframe before on the same pass: the drive along the keyframes between them
  // is long against the place's size. One walk back from the current keyframe gives every distance.
  std::sort(same_place.begin(), same_place.end(), [](KeyframeId a, KeyframeId b) { return a.value > b.value; });
  std::vector<KeyframeId> revisited;
  double path = 0.0;
  Eigen::Vector3d last = centre;
  auto next = same_place.begin();
  for (int v = id.value - 1; v >= 0 && next != same_place.end(); --v) {
    const Keyframe* kf = map_.keyframe(KeyframeId{v});
    if (kf == nullptr) continue;
    const Eigen::Vector3d c = kf->center();
    path += (c - last).norm();
    last = c;
    if (v != next->value) continue;
    if (path >= options_.revisit_path_ratio * radius) revisited.push_back(*next);
    ++next;
  }
  // The place keeps its first keyframe (the one loops were closed against, the anchor of the map
  // there), the current one and the newest others, max_keyframes_per_place in all; the rest go. The
  // first keyframe of the map and a map's root always stay (frames of a later map hang from a root).
  const auto keep = static_cast<std::size_t>(options_.max_keyframes_per_place);
  if (revisited.size() + 1 <= keep) return 0;
  int culled = 0;
  for (std::size_t i = keep - 2; i + 1 < revisited.size(); ++i) {  // newest first; the oldest is last
    // found in the map by the walk above; erasing others does not remove it
    if (revisited[i].value == 0 || !map_.keyframe(revisited[i])->parent.valid()) continue;
    map_.erase_keyframe(revisited[i]);
    ++culled;
  }
  return culled;
}

}  // namespace rgbl
