#include "rgbl/loop/loop_closer.hpp"

#include "rgbl/backend/map_bundle.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/geometry/se3.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <shared_mutex>
#include <span>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace rgbl {

void MapBridgeOptions::validate() const {
  require(std::isfinite(max_gap_s) && max_gap_s > 0.0, "loop_closing.bridge.max_gap_s", "> 0 s");
  registration.validate();
}

void LoopScanOptions::validate() const {
  require(std::isfinite(voxel) && voxel > 0.0, "loop_closing.scans.voxel", "> 0 m");
  require(std::isfinite(min_probe_loss) && min_probe_loss >= 0.0 && min_probe_loss <= 1.0,
          "loop_closing.scans.min_probe_loss", "a share in [0, 1]");
  require(std::isfinite(max_change_m) && max_change_m > 0.0, "loop_closing.scans.max_change_m", "> 0 m");
  require(std::isfinite(max_change_deg) && max_change_deg > 0.0, "loop_closing.scans.max_change_deg", "> 0 deg");
  registration.validate();
}

void LoopClosingOptions::validate() const {
  places.validate();
  scans.validate();
  require(max_candidates >= 1, "loop_closing.max_candidates", ">= 1 candidate");
  require(min_keyframe_gap >= 1, "loop_closing.min_keyframe_gap", ">= 1 keyframe");
  require(consistent_keyframes >= 1, "loop_closing.consistent_keyframes", ">= 1 keyframe");
  require(matched_side_keyframes <= 100, "loop_closing.matched_side_keyframes", "<= 100 keyframes");
  require(consistency_tolerance_m > 0.0, "loop_closing.consistency_tolerance_m", "> 0 m");
  require(consistency_tolerance_deg > 0.0, "loop_closing.consistency_tolerance_deg", "> 0 deg");
  require(min_correction_m >= 0.0, "loop_closing.min_correction_m", ">= 0 m");
  require(min_correction_deg >= 0.0, "loop_closing.min_correction_deg", ">= 0 deg");
  bridge.validate();
  require(max_drift_percent > 0.0, "loop_closing.max_drift_percent", "> 0 % of the distance driven");
  require(max_drift_deg_per_100m > 0.0, "loop_closing.max_drift_deg_per_100m", "> 0 deg per 100 m");
  require(drift_allowance_m >= 0.0, "loop_closing.drift_allowance_m", ">= 0 m");
  require(drift_allowance_deg >= 0.0, "loop_closing.drift_allowance_deg", ">= 0 deg");
  verification.validate();
  correction.validate();
  require(fusion_neighbours >= 0, "loop_closing.fusion_neighbours", ">= 0 keyframes");
  fusion.validate();
  global_ba_options.validate();
  global_ba_pairs.validate();
  require(global_ba_min_shared >= 0, "loop_closing.global_ba_min_shared", ">= 0 observations");
}

namespace {

// Spanning-tree roots, memoised for one query: keyframes of one map share the root, a map started
// after a loss has its own until a loop across the two merges them.
// Each keyframe is walked once per query, however many candidates ask.
class Roots {
 public:
  explicit Roots(const Map& map) : map_(map) {}

  KeyframeId operator()(KeyframeId id) {
    std::vector<int> path;
    KeyframeId root = id;
    // bounded: a cycle (never in a tree) ends the walk rather than looping forever
    for (std::size_t steps = 0; steps <= map_.keyframe_count(); ++steps) {
      if (const auto known = known_.find(root.value); known != known_.end()) {
        root = known->second;
        break;
      }
      const Keyframe* k = map_.keyframe(root);
      if (k == nullptr || !k->parent.valid()) break;
      path.push_back(root.value);
      root = k->parent;
    }
    for (const int v : path) known_[v] = root;
    return root;
  }

 private:
  const Map& map_;
  std::unordered_map<int, KeyframeId> known_;
};

// How far camera pose b is from a: centre distance and rotation angle.
struct PoseChange {
  double m = 0.0, deg = 0.0;
};
PoseChange pose_change(const Eigen::Isometry3d& T_cam_world_a, const Eigen::Isometry3d& T_cam_world_b) {
  return {(T_cam_world_b.inverse().translation() - T_cam_world_a.inverse().translation()).norm(),
          rotation_angle(T_cam_world_b.linear() * T_cam_world_a.linear().transpose()) * 180.0 / std::numbers::pi};
}

// Whether odometry can have drifted by `asked` over driven_m metres (LoopClosingOptions::max_drift_percent).
bool plausible_drift(const LoopClosingOptions& o, PoseChange asked, double driven_m) {
  return asked.m <= o.drift_allowance_m + 0.01 * o.max_drift_percent * driven_m &&
         asked.deg <= o.drift_allowance_deg + 0.01 * o.max_drift_deg_per_100m * driven_m;
}

// The loop must hold for more keyframe pairs than the one that found it (ORB-SLAM3 checks keyframes
// already in the map rather than waiting for new ones, which a loop ending where the drive ends never
// brings). Each pair is a guided verification of keyframe k against keyframe m from the pose the loop
// implies for k, and the pose it measures must be within the tolerances of that guess: for a keyframe
// before `current` this compares its loop-measured pose relative to `current` with the map's, which
// odometry knows to centimetres over a few keyframes. The keyframes before `current` are tried against
// the matched keyframe first, then `current` against the matched keyframe's best covisible ones. A
// pair that does not see the place is skipped; one that sees it and disagrees refuses the loop. The
// loop constraints of the consistent_keyframes - 1 pairs that confirmed, or nullopt.
std::optional<std::vector<LoopConstraint>> confirm(const PinholeCamera& camera, const LoopClosingOptions& options,
                                                   const Map& map, const Keyframe& current, const DetectedLoop& loop,
                                                   std::span<const KeyframeId> previous) {
  const Eigen::Isometry3d& T_cur_world_loop = loop.verification.T_cam_world;
  const KeyframeId matched = loop.verification.constraint.matched;
  const auto needed = static_cast<std::size_t>(options.consistent_keyframes - 1);
  std::vector<LoopConstraint> constraints;
  // false: the pair saw the place and disagrees
  const auto attempt = [&](const Keyframe& k, KeyframeId against, const Eigen::Isometry3d& T_k_world_guess) {
    LoopVerificationCounts counts;
    const auto again = verify_loop_guided(camera, k, map, against, T_k_world_guess, options.verification, &counts);
    if (!again) {
      logger()->debug("loop: keyframe {} vs {} does not confirm keyframe {} vs {} ({} matches, {} guided, {} inliers)",
                      k.id.value, against.value, current.id.value, matched.value, counts.matches,
                      counts.guided_matches, counts.inliers);
      return true;
    }
    const PoseChange disagreement = pose_change(T_k_world_guess, again->T_cam_world);
    if (disagreement.m > options.consistency_tolerance_m || disagreement.deg > options.consistency_tolerance_deg) {
      logger()->debug("loop: keyframe {} vs {} disagrees with keyframe {} vs {} by {:.3f} m, {:.2f} deg", k.id.value,
                      against.value, current.id.value, matched.value, disagreement.m, disagreement.deg);
      return false;
    }
    constraints.push_back(again->constraint);
    return true;
  };
  for (const KeyframeId id : previous) {
    if (constraints.size() >= needed) break;
    const Keyframe& k = *map.keyframe(id);
    // where the loop puts k: its pose relative to current as the map has it
    if (!attempt(k, matched, k.T_cam_world * current.T_cam_world.inverse() * T_cur_world_loop)) return std::nullopt;
  }
  if (constraints.size() < needed) {
    for (const KeyframeId other : map.best_covisible(matched, options.matched_side_keyframes)) {
      if (constraints.size() >= needed) break;
      if (current.covisibility.contains(other)) continue;
      if (!attempt(current, other, T_cur_world_loop)) return std::nullopt;
    }
  }
  if (constraints.size() < needed) return std::nullopt;
  return constraints;
}

// After the pose graph has brought the two sides together, the matched side's landmarks are fused into
// the current side's keyframes: a landmark seen on both laps becomes one, which ties the laps together
// for the bundle adjustment. Returns how many were fused.
int fuse_across(Map& map, const PinholeCamera& camera, const LoopClosingOptions& options, KeyframeId current,
                KeyframeId matched) {
  const auto neighbours = static_cast<std::size_t>(options.fusion_neighbours);
  const std::vector<KeyframeId> current_side = map.neighbourhood(current, neighbours);
  std::vector<KeyframeId> matched_side = map.neighbourhood(matched, neighbours);
  std::erase_if(matched_side, [&](KeyframeId k) {
    return std::find(current_side.begin(), current_side.end(), k) != current_side.end();
  });
  const std::vector<LandmarkId> landmarks = map.landmarks_seen_by(matched_side);
  int fused = 0;
  for (const KeyframeId k : current_side) fused += fuse_landmarks(map, camera, k, landmarks, options.fusion);
  if (fused == 0) return 0;
  for (const LandmarkId l : map.landmarks_seen_by(current_side)) map.update_landmark(l);
  for (const KeyframeId k : current_side) map.update_covisibility(k);
  for (const KeyframeId k : matched_side) map.update_covisibility(k);
  return fused;
}

constexpr std::string_view kBridgeSource = "lidar_bridge";

// The first keyframe of a map started after a loss, placed on the old map's last keyframe by
// registering its scan onto that keyframe's scan from where the new map was anchored (the motion
// model's guess over the gap). nullopt unless the registration converged, is a clear optimum and moves
// the new map no more than the guess can be off.
std::optional<DetectedLoop> bridge_maps(const MapBridgeOptions& o, const Eigen::Isometry3d& T_cam_lidar,
                                        const Keyframe& last, PointCloudView last_scan, const Keyframe& current,
                                        PointCloudView scan, TaskPool* pool) {
  const double gap = current.timestamp - last.timestamp;
  if (!(gap > 0.0 && gap <= o.max_gap_s)) {
    logger()->debug("bridge: keyframes {} and {} are {:.2f} s apart (at most {:.2f} s): not registered",
                    last.id.value, current.id.value, gap, o.max_gap_s);
    return std::nullopt;
  }
  const Stopwatch watch;
  const auto g = register_across_gap(last_scan, scan, T_cam_lidar, last.T_cam_world * current.T_cam_world.inverse(),
                                     gap, o.registration, pool);
  if (!g) {
    logger()->info("bridge: frame {} onto frame {}: too little to register", current.frame_index, last.frame_index);
    return std::nullopt;
  }
  const ScanRegistration& r = g->registration;
  const Eigen::Isometry3d& T_last_current = g->T_reference_query;
  const Eigen::Isometry3d T_current_world = T_last_current.inverse() * last.T_cam_world;
  logger()->info("bridge: frame {} onto frame {} ({:.2f} s, {:.1f} m apart): {} of {} starts converged, {} "
                 "iterations, {} correspondences, agreement {:.3f} (runner-up {:.3f}), probe loss {:.3f} (>= {:.2f}), "
                 "moves the new map {:.2f} m, {:.2f} deg (at most {:.2f} m, {:.2f} deg): {} ({:.0f} ms)",
                 current.frame_index, last.frame_index, gap, T_last_current.translation().norm(), r.converged_starts,
                 r.starts, r.iterations, r.correspondences, r.agreement, r.runner_up_agreement, r.min_probe_loss,
                 o.registration.min_probe_loss, g->moved_m, g->moved_deg, g->allowed_m, g->allowed_deg,
                 g->accepted ? "accepted" : "refused", watch.elapsed_ms());
  if (!g->accepted) return std::nullopt;
  DetectedLoop loop;
  loop.keyframe = current.id;
  loop.verification.T_cam_world = T_current_world;
  loop.verification.constraint = {current.id, last.id, T_last_current.inverse()};
  loop.verification.counts.inliers = static_cast<int>(r.correspondences);
  loop.place = {static_cast<std::size_t>(last.id.value), r.agreement, kBridgeSource};
  loop.bridge = true;
  return loop;
}

// Moves every keyframe and landmark of the map rooted at `root` by T_old_new (a point x of that map is
// at T_old_new * x in the matched map) and hangs its root from `matched`.
void merge_maps(Map& map, KeyframeId root, KeyframeId matched, const Eigen::Isometry3d& T_old_new) {
  Roots roots(map);
  std::vector<KeyframeId> moved;
  for (const KeyframeId k : map.keyframe_ids()) {
    if (roots(k) == root) moved.push_back(k);
  }
  const std::vector<LandmarkId> landmarks = map.landmarks_seen_by(moved);  // only its own: the maps share none
  const Eigen::Isometry3d T_new_old = T_old_new.inverse();
  for (const KeyframeId k : moved) {
    Keyframe& kf = *map.keyframe(k);
    kf.T_cam_world = kf.T_cam_world * T_new_old;
  }
  for (const LandmarkId l : landmarks) {  // after the keyframes: the viewing directions use their poses
    map.landmark(l)->position = T_old_new * map.landmark(l)->position;
    map.update_landmark(l);
  }
  map.keyframe(root)->parent = matched;
}

}  // namespace

LoopCloser::LoopCloser(const CameraCalibration& calibration, LoopClosingOptions options)
    : LoopCloser(calibration.camera, std::move(options)) {
  T_cam_lidar_ = calibration.T_cam_lidar;
}

LoopCloser::LoopCloser(const PinholeCamera& camera, LoopClosingOptions options)
    : camera_(camera), options_(std::move(options)) {
  options_.validate();
  for (const std::string& method : options_.places.methods) places_.push_back(make_place_recognizer(method, options_.places));
}

void LoopCloser::add_place_recognizer(std::unique_ptr<PlaceRecognizer> recognizer) {
  if (!recognizer) throw ConfigError("loop_closing.places", "a place recogniser, not null");
  places_.push_back(std::move(recognizer));
}

void LoopCloser::adjust_map(Map& map, KeyframeId keyframe, LoopClosure& closure) const {
  const Stopwatch watch;
  Roots roots(map);
  const KeyframeId root = roots(keyframe);
  std::vector<KeyframeId> tree = map.keyframe_ids();
  std::erase_if(tree, [&](KeyframeId k) { return roots(k) != root; });
  MapBundle bundle = make_map_bundle(map, tree, {}, root);
  // A keyframe whose landmarks have mostly been culled or fused away is barely determined by the
  // landmarks it shares: 2 observations left it free to slide metres at almost no cost (two laps of
  // 79.5 m, seed 3, first closure: 13.5 m with 50 iterations; docs/loop-closing.md). It is held during
  // the solve and then moved rigidly with its parent, as the pose graph moved it.
  std::vector<int> seen(bundle.problem.points.size(), 0);
  for (const BundleObservation& o : bundle.problem.observations) ++seen[static_cast<std::size_t>(o.point)];
  std::vector<int> shared(bundle.problem.poses.size(), 0);
  for (const BundleObservation& o : bundle.problem.observations) {
    if (seen[static_cast<std::size_t>(o.point)] > 1) ++shared[static_cast<std::size_t>(o.pose)];
  }
  std::vector<std::pair<KeyframeId, Eigen::Isometry3d>> held;  // with T_cam_parent before
  for (std::size_t i = 0; i < bundle.keyframes.size(); ++i) {
    if (bundle.problem.poses[i].fixed || shared[i] >= options_.global_ba_min_shared) continue;
    const Keyframe* kf = map.keyframe(bundle.keyframes[i]);
    const auto T_parent_world = map.keyframe_pose(kf->parent);
    if (!T_parent_world) continue;
    bundle.problem.poses[i].fixed = true;
    held.emplace_back(kf->id, kf->T_cam_world * T_parent_world->inverse());
  }
  add_keyframe_pairs(map, bundle, options_.global_ba_pairs);
  const BundleAdjustmentResult result = bundle_adjust(camera_, bundle.problem, options_.global_ba_options);
  closure.global_ba_keyframes = static_cast<int>(bundle.keyframes.size());
  closure.global_ba_landmarks = static_cast<int>(bundle.landmarks.size());
  closure.global_ba_held = static_cast<int>(held.size());
  closure.global_ba_outliers = apply_map_bundle(map, bundle, result);
  // parents are older: in id order each parent is placed before its children
  std::sort(held.begin(), held.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [k, T_cam_parent] : held) {
    Keyframe& kf = *map.keyframe(k);
    const Eigen::Isometry3d T_cam_world_before = kf.T_cam_world;
    kf.T_cam_world = T_cam_parent * *map.keyframe_pose(kf.parent);
    // what only this keyframe sees moves with it
    const Eigen::Isometry3d T_new_old = kf.T_cam_world.inverse() * T_cam_world_before;
    for (const LandmarkId l : kf.landmarks) {
      Landmark* landmark = l.valid() ? map.landmark(l) : nullptr;
      if (landmark != nullptr && landmark->observations.size() == 1) landmark->position = T_new_old * landmark->position;
    }
  }
  if (!held.empty()) {
    for (const LandmarkId l : map.landmarks_seen_by(tree)) map.update_landmark(l);
  }
  closure.global_ba_ms = watch.elapsed_ms();
}

double LoopCloser::record_odometry(KeyframeId keyframe, const Eigen::Vector3d& centre) {
  if (last_centre_) driven_total_m_ += (centre - *last_centre_).norm();
  last_centre_ = centre;
  const auto slot = static_cast<std::size_t>(keyframe.value);
  if (slot >= driven_m_.size()) driven_m_.resize(slot + 1, std::numeric_limits<double>::quiet_NaN());
  driven_m_[slot] = driven_total_m_;
  return driven_total_m_;
}

void LoopCloser::keep_scan(const Map& map, KeyframeId keyframe, PointCloudView scan) {
  if (!options_.scans.enabled || !T_cam_lidar_) return;
  std::erase_if(scans_, [&](const auto& entry) { return map.keyframe(KeyframeId{entry.first}) == nullptr; });
  if (!scan.empty()) scans_[keyframe.value] = voxel_downsample(scan, options_.scans.registration, options_.scans.voxel);
}

std::optional<LoopConstraint> LoopCloser::scan_refined(const LoopConstraint& c, PointCloudView current_scan) const {
  const auto matched = scans_.find(c.matched.value);
  PointCloudView query = current_scan;
  if (const auto current = scans_.find(c.current.value); query.empty() && current != scans_.end()) query = current->second;
  if (matched == scans_.end() || query.empty()) return std::nullopt;
  const Eigen::Isometry3d& T_cam_lidar = *T_cam_lidar_;
  // the images' measurement between the two LiDAR frames: matched <- current
  const Eigen::Isometry3d guess = T_cam_lidar.inverse() * c.T_current_matched.inverse() * T_cam_lidar;
  const LoopScanOptions& o = options_.scans;
  const auto r = register_scans(matched->second, query, guess, o.registration, pool_.get());
  if (!r) {
    logger()->debug("loop: keyframes {} and {}: too little in their scans to register", c.current.value,
                    c.matched.value);
    return std::nullopt;
  }
  LoopConstraint refined = c;
  refined.T_current_matched = (T_cam_lidar * r->T_reference_query * T_cam_lidar.inverse()).inverse();
  // the current camera's centre and turn in the matched camera's frame, images against scans
  const PoseChange change = pose_change(c.T_current_matched, refined.T_current_matched);
  const bool ok = r->converged && r->min_probe_loss >= o.min_probe_loss && change.m <= o.max_change_m &&
                  change.deg <= o.max_change_deg;
  logger()->debug("loop: keyframe {} vs {} by the scans: {:.3f} m, {:.2f} deg from the images' ({} iterations, {}, "
                  "probe loss {:.3f}): {}",
                  c.current.value, c.matched.value, change.m, change.deg, r->iterations,
                  r->converged ? "converged" : "not converged", r->min_probe_loss, ok ? "taken" : "the images' kept");
  if (!ok) return std::nullopt;
  return refined;
}

void LoopCloser::remember(KeyframeId keyframe) {
  recent_.push_back(keyframe);
  if (std::cmp_greater(recent_.size(), options_.consistent_keyframes)) recent_.erase(recent_.begin());
}

LoopCloserStep LoopCloser::process(Map& map, KeyframeId keyframe, PointCloudView scan) {
  std::optional<DetectedLoop> loop;
  LoopCloserStep step = detect(map, keyframe, scan, loop);
  if (loop) {
    std::unique_lock lock(map.mutex());
    correct(map, *loop, step);
  }
  return step;
}

LoopCloserStep LoopCloser::detect(Map& map, KeyframeId keyframe, PointCloudView scan, std::optional<DetectedLoop>& loop) {
  loop.reset();
  LoopCloserStep step;
  if (!options_.enabled) return step;
  const Stopwatch watch;
  const auto done = [&] {
    step.time_ms = watch.elapsed_ms();
    stats_.time_ms += step.time_ms;
    return step;
  };
  ++stats_.keyframes;
  std::optional<DetectedLoop> best;  // the verified candidate with the most inliers
  KeyframeId root;  // of the current keyframe's map
  {
    std::shared_lock lock(map.mutex());
    const Keyframe* current = map.keyframe(keyframe);
    if (current == nullptr) return done();
    keep_scan(map, keyframe, scan);
    const double driven = record_odometry(keyframe, current->center());
    Roots roots(map);
    root = roots(keyframe);
    const auto allowed = [&](std::size_t id) {
      const KeyframeId candidate{static_cast<int>(id)};
      return candidate.value <= keyframe.value - options_.min_keyframe_gap && map.keyframe(candidate) != nullptr &&
             !current->covisibility.contains(candidate) && (options_.merge_maps || roots(candidate) == root);
    };
    // A new map's first keyframe: bridged to the map before it if the scans register (then no place
    // is asked for: the bridge is the merge).
    bool bridged = false;
    const Keyframe* last = last_keyframe_.valid() ? map.keyframe(last_keyframe_) : nullptr;
    if (options_.merge_maps && options_.bridge.enabled && T_cam_lidar_ && last != nullptr && !current->parent.valid() &&
        roots(last_keyframe_) != root && !scan.empty() && !last_scan_.empty()) {
      ++stats_.bridge_attempts;
      best = bridge_maps(options_.bridge, *T_cam_lidar_, *last, last_scan_, *current, scan, pool_.get());
      bridged = best.has_value();
    }
    std::vector<std::size_t> neighbours;
    for (const KeyframeId k : map.best_covisible(keyframe, options_.place_neighbours)) {
      neighbours.push_back(static_cast<std::size_t>(k.value));
    }
    const PlaceQuery query{static_cast<std::size_t>(keyframe.value), scan, current->descriptors, neighbours};
    // Places of every map (one of another map, started after a loss, is a merge candidate), each
    // recogniser's best in turn: its first, then every second, and so on; a place two name is
    // verified once.
    std::vector<std::vector<PlaceCandidate>> proposed;
    if (!bridged) {
      for (const auto& recognizer : places_) {
        proposed.push_back(recognizer->query(query, allowed, options_.max_candidates));
      }
    }
    std::vector<PlaceCandidate> candidates;
    for (std::size_t rank = 0; rank < options_.max_candidates; ++rank) {
      for (const auto& list : proposed) {
        if (rank >= list.size()) continue;
        const PlaceCandidate& c = list[rank];
        if (std::none_of(candidates.begin(), candidates.end(), [&](const auto& o) { return o.id == c.id; })) {
          candidates.push_back(c);
        }
      }
    }
    for (const PlaceCandidate& place : candidates) {
      const KeyframeId candidate{static_cast<int>(place.id)};
      ++step.candidates;
      LoopVerificationCounts counts;
      auto verified = verify_loop(camera_, *current, map, candidate, options_.verification, &counts);
      logger()->debug("loop: keyframe {} vs {}{} ({} {:.3f}): {} matches, {} RANSAC inliers, {} guided, {} "
                      "inliers{}",
                      keyframe.value, candidate.value, roots(candidate) == root ? "" : " of another map", place.source,
                      place.similarity,
                      counts.matches, counts.ransac_inliers, counts.guided_matches, counts.inliers,
                      verified ? ": verified" : "");
      if (!verified) continue;
      ++step.verified;
      const PoseChange asked = pose_change(current->T_cam_world, verified->T_cam_world);
      const double driven_since = driven - driven_m_[static_cast<std::size_t>(candidate.value)];
      if (!plausible_drift(options_, asked, driven_since)) {
        logger()->debug("loop: keyframe {} vs {} refused: it would move the map {:.2f} m, {:.2f} deg after {:.1f} m "
                        "driven",
                        keyframe.value, candidate.value, asked.m, asked.deg, driven_since);
        ++step.implausible;
        continue;
      }
      if (!best || verified->counts.inliers > best->verification.counts.inliers) {
        best = DetectedLoop{keyframe, std::move(*verified), place, {}, false};
      }
    }
    step.consistent = bridged;
    if (best && !bridged) {
      std::vector<KeyframeId> previous;  // the newest live ones, newest first
      for (auto it = recent_.rbegin();
           it != recent_.rend() && std::cmp_less(previous.size() + 1, options_.consistent_keyframes); ++it) {
        if (map.keyframe(*it) != nullptr && roots(*it) == root) previous.push_back(*it);
      }
      if (auto constraints = confirm(camera_, options_, map, *current, *best, previous)) {
        step.consistent = true;
        best->confirmations = std::move(*constraints);
      }
    }
    for (const auto& recognizer : places_) recognizer->add(query);  // under the lock: reads the descriptors
  }
  remember(keyframe);
  if (options_.merge_maps && options_.bridge.enabled && T_cam_lidar_) {
    last_keyframe_ = keyframe;
    last_scan_.assign(scan.begin(), scan.end());
  }
  stats_.candidates += step.candidates;
  stats_.verified += step.verified;
  stats_.implausible += step.implausible;
  if (!step.consistent) return done();
  ++stats_.consistent;
  if (options_.scans.enabled && T_cam_lidar_ && !best->bridge) {
    // outside the map's lock: the scans and the constraints are the loop closer's own
    const auto measure_again = [&](LoopConstraint& c) {
      const std::optional<LoopConstraint> refined = scan_refined(c, c.current == keyframe ? scan : PointCloudView{});
      ++(refined ? stats_.scan_refined : stats_.scan_kept);
      if (refined) c = *refined;
    };
    LoopVerification& v = best->verification;
    const Eigen::Isometry3d T_matched_world = v.constraint.T_current_matched.inverse() * v.T_cam_world;
    measure_again(v.constraint);
    v.T_cam_world = v.constraint.T_current_matched * T_matched_world;
    for (LoopConstraint& c : best->confirmations) measure_again(c);
  }
  loop = std::move(best);
  return done();
}

void LoopCloser::correct(Map& map, const DetectedLoop& loop, LoopCloserStep& step) {
  const Stopwatch watch;
  apply(map, loop, step);
  step.time_ms += watch.elapsed_ms();
  stats_.time_ms += watch.elapsed_ms();
  if (!step.closure) return;
  LoopClosure& c = *step.closure;
  c.time_ms = step.time_ms;  // detection and correction
  logger()->info("{}: frame {} with frame {} ({} {:.2f}, {} inliers): moved {:.2f} m, {:.2f} deg, "
                 "loop error {:.2f} -> {:.3f} m, keyframes moved up to {:.2f} m, {} landmarks fused, global BA {} "
                 "keyframes {:.0f} ms, {:.0f} ms",
                 c.bridged ? "maps bridged" : c.merged ? "maps merged" : "loop closed", c.frame_index,
                 c.matched_frame_index, c.place_source,
                 c.place_similarity, c.inliers, c.correction_m, c.correction_deg, c.correction.loop_error_before_m,
                 c.correction.loop_error_after_m, c.correction.max_keyframe_shift_m, c.fused_landmarks,
                 c.global_ba_keyframes, c.global_ba_ms, c.time_ms);
}

void LoopCloser::apply(Map& map, const DetectedLoop& loop, LoopCloserStep& step) {
  const KeyframeId keyframe = loop.keyframe;
  const KeyframeId matched = loop.verification.constraint.matched;
  // In a thread of its own, mapping may have culled either side since detection.
  if (map.keyframe(keyframe) == nullptr || map.keyframe(matched) == nullptr) return;
  Roots roots(map);
  const KeyframeId root = roots(keyframe);
  const bool merge = roots(matched) != root;
  const Eigen::Isometry3d T_cam_world_before = *map.keyframe_pose(keyframe);
  // How far the map is from the loop's measurement at the current keyframe.
  const PoseChange disagreement = pose_change(T_cam_world_before, loop.verification.T_cam_world);
  if (!merge && disagreement.m <= options_.min_correction_m && disagreement.deg <= options_.min_correction_deg) {
    logger()->debug("loop: keyframe {} confirms keyframe {} ({:.3f} m, {:.2f} deg off): no correction", keyframe.value,
                    matched.value, disagreement.m, disagreement.deg);
    ++stats_.confirming;
    return;
  }
  ++stats_.closures;
  loops_.push_back(loop.verification.constraint);
  loops_.insert(loops_.end(), loop.confirmations.begin(), loop.confirmations.end());
  // Culling may have erased keyframes of earlier loops; their edges go with them.
  std::erase_if(loops_, [&](const LoopConstraint& l) {
    return map.keyframe(l.current) == nullptr || map.keyframe(l.matched) == nullptr;
  });

  LoopClosure closure;
  closure.current = keyframe;
  closure.matched = matched;
  closure.frame_index = map.keyframe(keyframe)->frame_index;
  closure.matched_frame_index = map.keyframe(matched)->frame_index;
  closure.place_source = std::string(loop.place.source);
  closure.place_similarity = loop.place.similarity;
  closure.inliers = loop.verification.counts.inliers;
  if (merge) {
    // The current map moves rigidly onto the matched one (metric depth: no scale), and its root hangs
    // from the matched keyframe: one spanning tree, which the pose graph and bundle adjustment below
    // then treat as one map.
    const Eigen::Isometry3d T_old_new = loop.verification.T_cam_world.inverse() * T_cam_world_before;
    merge_maps(map, root, matched, T_old_new);
    closure.merged = true;
    closure.bridged = loop.bridge;
    ++stats_.merges;
    stats_.bridges += closure.bridged ? 1 : 0;
  }
  closure.correction = correct_loops(map, loops_, options_.correction);
  // Not across a bridge: its two keyframes are 7-33 m apart and share few landmarks, and the few a
  // fusion finds there (7 in a foliage scenario) become the only tie between the maps in local BA,
  // which then turned the new map 6 deg about them; unfused, the new map keeps the registered pose.
  if (options_.fuse && !closure.bridged) {
    closure.fused_landmarks = fuse_across(map, camera_, options_, keyframe, matched);
  }
  if (options_.global_ba) adjust_map(map, keyframe, closure);
  const PoseChange moved = pose_change(T_cam_world_before, *map.keyframe_pose(keyframe));
  last_centre_ = map.keyframe(keyframe)->center();  // odometry goes on from the corrected map
  closure.correction_m = moved.m;
  closure.correction_deg = moved.deg;
  step.closure = std::move(closure);
}

}  // namespace rgbl
