#pragma once
// Bundle adjustment of (part of) a Map: the problem is built from keyframes and the landmarks they
// observe, solved by bundle_adjust (on copies, so the solve itself needs no map lock), and written
// back. Local mapping adjusts a keyframe's neighbourhood; loop closing adjusts the whole map.

#include "rgbl/backend/bundle_adjustment.hpp"
#include "rgbl/map/map.hpp"

#include <span>
#include <utility>
#include <vector>

namespace rgbl {

// A BundleProblem and which map element each of its poses, points and observations stands for.
struct MapBundle {
  BundleProblem problem;
  std::vector<KeyframeId> keyframes;  // per problem pose
  std::vector<LandmarkId> landmarks;  // per problem point
  std::vector<std::pair<LandmarkId, KeyframeId>> observations;  // per problem observation
};

// Poses: the `window` keyframes (optimised, except `held`, which stays put as the gauge; invalid =
// none), then the `anchors` (fixed). Points: the landmarks observed by the window keyframes (ascending
// id). Residuals: their observations in window and anchor keyframes (sigma scale^level px, a depth
// residual where the keypoint has depth). Erased keyframes are skipped. Call with the map's lock held
// (shared is enough).
MapBundle make_map_bundle(const Map& map, std::span<const KeyframeId> window, std::span<const KeyframeId> anchors,
                          KeyframeId held = {});

// Writes the solved poses (not the fixed ones) and points back, erases the observations the solve
// called outliers and, when there were any, recomputes the covisibility of the bundle's keyframes.
// Returns how many observations it erased. Elements erased meanwhile are skipped. Call with the map's
// lock held exclusively.
int apply_map_bundle(Map& map, const MapBundle& bundle, const BundleAdjustmentResult& result);

}  // namespace rgbl
