#include "rgbl/loop/loop_closer.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <shared_mutex>
#include <utility>

namespace rgbl {

void LoopClosingOptions::validate() const {
  scan_context.validate();
  require(max_place_distance > 0.0 && max_place_distance <= 1.0, "loop_closing.max_place_distance",
          "a Scan Context distance in (0, 1]");
  require(ring_key_neighbours >= 1, "loop_closing.ring_key_neighbours", ">= 1 place");
  require(max_candidates >= 1, "loop_closing.max_candidates", ">= 1 candidate");
  require(min_keyframe_gap >= 1, "loop_closing.min_keyframe_gap", ">= 1 keyframe");
  require(consistent_keyframes >= 1, "loop_closing.consistent_keyframes", ">= 1 keyframe");
  require(consistency_tolerance_m > 0.0, "loop_closing.consistency_tolerance_m", "> 0 m");
  require(consistency_tolerance_deg > 0.0, "loop_closing.consistency_tolerance_deg", "> 0 deg");
  require(min_correction_m >= 0.0, "loop_closing.min_correction_m", ">= 0 m");
  require(min_correction_deg >= 0.0, "loop_closing.min_correction_deg", ">= 0 deg");
  verification.validate();
  correction.validate();
}

namespace {

// The spanning-tree root of a keyframe: keyframes of one map share it; a map started after a loss has
// its own (a loop across two maps is a merge, which needs more than a pose graph).
KeyframeId root_of(const Map& map, KeyframeId id) {
  for (std::size_t steps = 0; steps <= map.keyframe_count(); ++steps) {
    const Keyframe* k = map.keyframe(id);
    if (k == nullptr || !k->parent.valid()) return id;
    id = k->parent;
  }
  return id;  // unreachable for a tree; a cycle would end here rather than loop forever
}

struct Verified {
  LoopVerification verification;
  double place_distance = 0.0;
};

double angle_deg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / std::numbers::pi; }

}  // namespace

LoopCloser::LoopCloser(const PinholeCamera& camera, LoopClosingOptions options)
    : camera_(camera), options_(std::move(options)) {
  options_.validate();
}

LoopCloserStep LoopCloser::process(Map& map, KeyframeId keyframe, PointCloudView scan) {
  LoopCloserStep step;
  if (!options_.enabled) return step;
  const Stopwatch watch;
  if (scan.empty()) {
    recent_.push_back(keyframe);  // still a keyframe whose verification later loops may ask for
    if (recent_.size() > static_cast<std::size_t>(options_.consistent_keyframes)) recent_.erase(recent_.begin());
    step.time_ms = watch.elapsed_ms();
    return step;
  }
  ScanContext context = make_scan_context(scan, options_.scan_context);

  std::optional<Verified> best;
  std::vector<LoopConstraint> consistent;  // the earlier keyframes' verifications of the same loop
  {
    std::shared_lock lock(map.mutex());
    const Keyframe* current = map.keyframe(keyframe);
    if (current == nullptr) {
      step.time_ms = watch.elapsed_ms();
      return step;
    }
    const KeyframeId root = root_of(map, keyframe);
    const auto allowed = [&](std::size_t id) {
      const KeyframeId candidate{static_cast<int>(id)};
      return candidate.value <= keyframe.value - options_.min_keyframe_gap && map.keyframe(candidate) != nullptr &&
             !current->covisibility.contains(candidate) && root_of(map, candidate) == root;
    };
    const auto places = places_.query(context, options_.ring_key_neighbours, allowed);
    if (!places.empty()) {
      logger()->debug("loop: keyframe {} (frame {}): nearest place keyframe {} at {:.3f}", keyframe.value,
                      current->frame_index, places.front().id, places.front().match.distance);
    }
    for (const auto& place : places) {
      if (place.match.distance > options_.max_place_distance) break;  // sorted, best first
      if (std::cmp_greater_equal(step.candidates, options_.max_candidates)) break;
      ++step.candidates;
      const KeyframeId candidate{static_cast<int>(place.id)};
      LoopVerificationCounts counts;
      auto verified = verify_loop(camera_, *current, map, candidate, options_.verification, &counts);
      logger()->debug("loop: keyframe {} vs {} (place {:.3f}): {} matches, {} RANSAC inliers, {} inliers{}",
                      keyframe.value, candidate.value, place.match.distance, counts.matches, counts.ransac_inliers,
                      counts.inliers, verified ? ": verified" : "");
      if (!verified) continue;
      ++step.verified;
      if (!best || verified->counts.inliers > best->verification.counts.inliers) {
        best = Verified{std::move(*verified), place.match.distance};
      }
    }
    // The loop must hold for the keyframes before this one too (ORB-SLAM3 checks covisible keyframes
    // already in the map rather than waiting for new ones, which a loop ending where the drive ends
    // never brings): each verifies against the same matched region, and its measured pose relative to
    // this keyframe agrees with the map's, which odometry knows to centimetres over a few keyframes.
    if (best) {
      std::vector<KeyframeId> previous;
      for (auto it = recent_.rbegin(); it != recent_.rend() && std::cmp_less(previous.size() + 1, options_.consistent_keyframes); ++it) {
        if (map.keyframe(*it) != nullptr) previous.push_back(*it);
      }
      step.consistent = std::cmp_equal(previous.size() + 1, options_.consistent_keyframes);
      const Eigen::Isometry3d& T_cur_world_loop = best->verification.T_cam_world;
      const Eigen::Isometry3d& T_cur_world_map = current->T_cam_world;
      for (const KeyframeId id : previous) {
        if (!step.consistent) break;
        const Keyframe& k = *map.keyframe(id);
        LoopVerificationCounts counts;
        // its pose in the loop's frame if the map is right between the two keyframes
        const Eigen::Isometry3d T_k_world_guess = k.T_cam_world * T_cur_world_map.inverse() * T_cur_world_loop;
        const auto again = verify_loop_guided(camera_, k, map, best->verification.constraint.matched, T_k_world_guess,
                                              options_.verification, &counts);
        if (!again) {
          logger()->debug("loop: keyframe {} verified keyframe {} but keyframe {} does not ({} matches, {} RANSAC "
                          "inliers, {} inliers)",
                          keyframe.value, best->verification.constraint.matched.value, id.value, counts.matches,
                          counts.ransac_inliers, counts.inliers);
          step.consistent = false;
          break;
        }
        const Eigen::Isometry3d loop_rel = T_cur_world_loop * again->T_cam_world.inverse();
        const Eigen::Isometry3d map_rel = T_cur_world_map * k.T_cam_world.inverse();
        const Eigen::Isometry3d diff = loop_rel.inverse() * map_rel;
        const double diff_m = diff.translation().norm(), diff_deg = angle_deg(diff.rotation());
        if (diff_m > options_.consistency_tolerance_m || diff_deg > options_.consistency_tolerance_deg) {
          logger()->debug("loop: keyframe {} and {} disagree on the loop by {:.3f} m, {:.2f} deg", keyframe.value,
                          id.value, diff_m, diff_deg);
          step.consistent = false;
          break;
        }
        consistent.push_back(again->constraint);
      }
    }
  }
  places_.add(static_cast<std::size_t>(keyframe.value), std::move(context));
  recent_.push_back(keyframe);
  if (recent_.size() > static_cast<std::size_t>(options_.consistent_keyframes)) recent_.erase(recent_.begin());
  if (!best || !step.consistent) {
    step.time_ms = watch.elapsed_ms();
    return step;
  }

  std::unique_lock lock(map.mutex());
  const Verified& accepted = *best;
  const Eigen::Isometry3d T_cam_world_before = *map.keyframe_pose(keyframe);
  // How far the map is from the loop's measurement at the current keyframe.
  const Eigen::Isometry3d& T_cam_world_loop = accepted.verification.T_cam_world;
  const double disagreement_m = (T_cam_world_loop.inverse().translation() - T_cam_world_before.inverse().translation()).norm();
  const double disagreement_deg = angle_deg(T_cam_world_loop.rotation() * T_cam_world_before.rotation().transpose());
  if (disagreement_m <= options_.min_correction_m && disagreement_deg <= options_.min_correction_deg) {
    logger()->debug("loop: keyframe {} confirms keyframe {} ({:.3f} m, {:.2f} deg off): no correction", keyframe.value,
                    accepted.verification.constraint.matched.value, disagreement_m, disagreement_deg);
    step.time_ms = watch.elapsed_ms();
    return step;
  }
  loops_.push_back(accepted.verification.constraint);
  loops_.insert(loops_.end(), consistent.begin(), consistent.end());
  // Culling may have erased keyframes of earlier loops; their edges go with them.
  std::erase_if(loops_, [&](const LoopConstraint& l) {
    return map.keyframe(l.current) == nullptr || map.keyframe(l.matched) == nullptr;
  });

  LoopClosure closure;
  closure.current = keyframe;
  closure.matched = accepted.verification.constraint.matched;
  closure.frame_index = map.keyframe(keyframe)->frame_index;
  closure.matched_frame_index = map.keyframe(closure.matched)->frame_index;
  closure.place_distance = accepted.place_distance;
  closure.inliers = accepted.verification.counts.inliers;
  closure.correction = correct_loops(map, loops_, options_.correction);
  const Eigen::Isometry3d T_cam_world_after = *map.keyframe_pose(keyframe);
  closure.correction_m = (T_cam_world_after.inverse().translation() - T_cam_world_before.inverse().translation()).norm();
  closure.correction_deg = angle_deg(T_cam_world_after.rotation() * T_cam_world_before.rotation().transpose());
  closure.time_ms = watch.elapsed_ms();
  logger()->info("loop closed: frame {} with frame {} (place {:.2f}, {} inliers): moved {:.2f} m, {:.2f} deg, "
                 "loop error {:.2f} -> {:.3f} m, {:.0f} ms",
                 closure.frame_index, closure.matched_frame_index, closure.place_distance, closure.inliers,
                 closure.correction_m, closure.correction_deg, closure.correction.loop_error_before_m,
                 closure.correction.loop_error_after_m, closure.time_ms);
  step.closure = closure;
  step.time_ms = closure.time_ms;
  return step;
}

}  // namespace rgbl
