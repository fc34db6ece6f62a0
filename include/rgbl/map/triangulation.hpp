#pragma once
// Landmarks for keypoints the LiDAR gives no depth: matched between a new keyframe and its covisible
// keyframes along the epipolar line and triangulated from the two rays (ORB-SLAM3's local mapping makes
// them for every sensor). On KITTI two thirds of the keypoints have no depth, most of them far: the
// points that pin rotation best. A keypoint whose nearest depth-bearing neighbour lies on something
// the tracker found moving (Keyframe::depth_sigma 0 with a depth) is left out.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"

#include <vector>

namespace rgbl {

struct TriangulationOptions {
  int covisible_keyframes = 10;      // the neighbours searched (ORB-SLAM3: 10 for stereo and RGB-D)
  int max_hamming = 50;              // descriptor distance of an accepted match (the matcher's usual bound)
  double max_ratio = 0.8;            // best against second best along the line (Lowe's test)
  double min_parallax_deg = 1.0;     // angle between the two rays at the point
  double min_depth = 0.5;            // m; the nearest point searched for along a keypoint's ray
  // The triangulated depth's sigma against the depth, from the two keypoints' level sigmas over the
  // parallax: sqrt(s_own^2 + s_other^2) / fx / parallax (radians). A 1 deg bound alone keeps points
  // known to 11 % (KITTI, level 0) or 23 % (the simulator's half-size images), worse at higher levels;
  // on the simulator's repeated street 15 % of those came out more than 50 % off (docs/accuracy.md).
  double max_depth_sigma_relative = 0.1;
  // The baseline against the neighbour's median depth below which a pair is not searched (the rays
  // would be nearly parallel for most of the scene).
  double min_baseline_ratio = 0.01;
  // A keypoint is left out when its nearest keypoint with a depth within this radius is on something
  // moving; 2 grid cells of the feature grid.
  double moving_radius_px = 32.0;
  // Also keypoints whose depth the noise model refused (Keyframe::depth_refused, mostly depth edges).
  // Off: a corner on a depth edge is often where a near outline crosses a far surface in the image,
  // which moves with the view and triangulates to no point at all.
  bool include_refused_depth = false;

  void validate() const;
};

// Matches keyframe `id`'s keypoints without depth and landmark with those of its best covisible
// keyframes (epipolar distance within chi2(1) at 95 % of the pyramid level's pixel sigma, Hamming
// distance, ratio test, one-to-one), triangulates each match (in front of both cameras, reprojection
// within chi2(2) at 95 % in both, parallax, distance ratio consistent with the pyramid levels) and adds
// the landmarks with their two observations. Returns the new landmarks. The caller holds the map lock
// exclusively.
std::vector<LandmarkId> triangulate_landmarks(Map& map, const PinholeCamera& camera, KeyframeId id,
                                              const TriangulationOptions& options = {});

}  // namespace rgbl
