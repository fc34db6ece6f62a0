#pragma once
// Loop correction of a map: the essential graph (spanning tree, strong covisibility, loop edges) as a
// pose graph on SE(3), optimised, then written back: every keyframe gets its optimised pose and every
// landmark moves rigidly with its reference keyframe. Frames tracked against a keyframe follow it, so
// trajectories written after the correction are the corrected ones.
//
// Not here: finding and verifying the loop (rgbl/loop), fusing the landmarks across it
// (rgbl/map/fusion.hpp) and the bundle adjustment of the whole map that follows (map_bundle.hpp); the
// LoopCloser runs them in that order.

#include "rgbl/backend/pose_graph.hpp"
#include "rgbl/map/map.hpp"

#include <Eigen/Geometry>

#include <vector>

namespace rgbl {

// A verified loop: the relative pose between the current keyframe and the matched (older) one,
// measured by geometric verification: T_current_matched maps points of the matched keyframe's camera
// frame into the current one's.
struct LoopConstraint {
  KeyframeId current;
  KeyframeId matched;
  Eigen::Isometry3d T_current_matched = Eigen::Isometry3d::Identity();
};

struct LoopCorrectionOptions {
  // Covisibility edges join keyframes sharing at least this many landmarks (ORB-SLAM's essential
  // graph uses 100); the spanning tree is always in.
  int min_covisibility = 100;
  // All edges get the same sigmas (only their ratio matters without other information): 2 cm per
  // 0.002 rad, i.e. a rotation error counts as much as a translation error at 10 m.
  double sigma_translation = 0.02;  // m
  double sigma_rotation = 0.002;    // rad
  PoseGraphOptions graph;

  void validate() const;
};

struct LoopCorrectionResult {
  std::size_t keyframes = 0;    // nodes of the graph
  std::size_t edges = 0;        // spanning tree + covisibility + loop edges
  std::size_t landmarks = 0;    // landmarks moved with their reference keyframe
  double max_keyframe_shift_m = 0.0;  // largest change of a keyframe centre
  double loop_error_before_m = 0.0;   // |translation| of the loop edges' error before / after, worst
  double loop_error_after_m = 0.0;
  bool converged = false;
};

// Corrects `map` in place. The root keyframe (the map's first, with no parent) is held fixed. Call with
// the map's mutex held exclusively (Map does not lock itself). Throws ConfigError when a loop names a
// keyframe the map does not hold.
LoopCorrectionResult correct_loops(Map& map, const std::vector<LoopConstraint>& loops,
                                   const LoopCorrectionOptions& options = {});

}  // namespace rgbl
