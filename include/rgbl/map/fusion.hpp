#pragma once
// Landmark fusion: landmarks projected into a keyframe are matched to its keypoints near where they
// project (pixel and depth chi2 gates, descriptor distance); a keypoint without a landmark gains the
// observation, a keypoint that already has one is a duplicate and the two become one. Local mapping
// fuses a new keyframe with its neighbours; loop closing fuses the two sides of a closed loop.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"

#include <span>

namespace rgbl {

struct FusionOptions {
  double radius_px = 3.0;  // search radius at pyramid level 0, scaled by scale_factor^level
  int max_hamming = 50;    // descriptor distance of an accepted match
  double min_view_cos = 0.5;  // viewing direction within 60 deg of the landmark's mean one

  void validate() const;
};

// Fuses `landmarks` into keyframe `target`; returns how many were fused (observations added or
// duplicates merged). When two landmarks merge, the one with more observations survives. Landmarks
// the target already observes or cannot see (view_landmark with options.min_view_cos) are skipped. Call with the map's lock held
// exclusively. Does not recompute descriptors or covisibility: the caller does, once, afterwards.
int fuse_landmarks(Map& map, const PinholeCamera& camera, KeyframeId target, std::span<const LandmarkId> landmarks,
                   const FusionOptions& options = {});

}  // namespace rgbl
