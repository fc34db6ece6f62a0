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

// What ties keyframes to one another besides the landmarks they share: the measurements local BA
// and the global BA after a loop add between keyframes (0 in a pair kind's sigma turns it off).
struct KeyframePairOptions {
  // The road: each optimised keyframe with a road plane in its scan is paired with the newest older
  // keyframe of the problem that has one (BundlePlanePair), fixing their relative height and tilt.
  // Where keyframes share few points (a car ahead hides the street) a window otherwise drifts up or
  // down as a whole. Sigmas from KITTI 04's ground truth, road planes 5-10 frames apart (0.04-0.07 m,
  // 0.4-0.6 deg median).
  double road_sigma_offset = 0.05;   // m
  double road_sigma_tilt_deg = 0.5;  // deg
  double road_max_distance = 20.0;   // m between the two: each plane is fitted to returns within 40 m
  // The motion tracking measured from the keyframe before (Keyframe::previous) ties each optimised
  // keyframe to that one (BundlePosePair). Landmarks seen by fewer than 3 keyframes are culled, and
  // with them most of what tied a keyframe to the one before: on the simulator's 400 m loop 18 points
  // tied a window to its fixed keyframes, and local BA moved new keyframes 0.1-0.3 m sideways against
  // a step tracking had right. Where both keyframes saw the road, the pair leaves height and tilt to
  // the road pair. Sigmas per axis between two keyframes; 0.1 m chosen over 0.05 m on the whole suite
  // and the loop table (docs/accuracy.md, "Keyframes keep the tracked motion").
  double odometry_sigma_translation = 0.1;  // m
  double odometry_sigma_rotation = 0.005;   // rad
  // The motion the two keyframes' LiDAR scans measure (Keyframe::T_cam_previous_lidar, registered
  // by local mapping) ties each optimised keyframe to its previous one as well (BundlePosePair, all
  // six axes): the scans measure the step without the keypoints' depth, the ring pattern or the
  // extrinsic angles' effect on the far road. Sigmas: over 290 keyframe pairs of the simulator's
  // streets the registered step is off the truth by 0.004 m (median) and 0.020 m (p90), and turns
  // 0.09 deg (median) from the tracked one (docs/accuracy.md, "Keyframes tied by their scans").
  // 0 = off.
  double lidar_sigma_translation = 0.02;  // m
  double lidar_sigma_rotation = 0.002;    // rad
  // A pair that lies within one sigma of the tracked motion's own pair (odometry_sigma_translation and
  // odometry_sigma_rotation) from the tracked motion takes this translation sigma instead (0 =
  // lidar_sigma_translation; none agrees while the odometry pair is off): two sensors that agree are
  // trusted more than either, and one that a moving object fools (a restart in stop-and-go traffic
  // registered 0.26 m short, 0.12-0.26 m from the tracked step) keeps the looser sigma. 0.01 m over
  // 0.015 and 0.02 m for all pairs on the whole suite, five samples (docs/accuracy.md, "Scan pairs
  // that agree with tracking trusted more").
  double lidar_agreeing_sigma_translation = 0.01;  // m

  void validate() const;  // throws ConfigError naming the field
};

// Adds the pairs of KeyframePairOptions to the bundle's problem for each keyframe it optimises: a
// road pair with the newest older keyframe of the problem that saw the road within
// road_max_distance, and a motion pair with its previous keyframe if that is in the problem (level
// only where both saw the road). Call with the map's lock held (shared is enough).
void add_keyframe_pairs(const Map& map, MapBundle& bundle, const KeyframePairOptions& options);

// Writes the solved poses (not the fixed ones) and points back, erases the observations the solve
// called outliers and, when there were any, recomputes the covisibility of the bundle's keyframes.
// Returns how many observations it erased. Elements erased meanwhile are skipped. Call with the map's
// lock held exclusively.
int apply_map_bundle(Map& map, const MapBundle& bundle, const BundleAdjustmentResult& result);

}  // namespace rgbl
