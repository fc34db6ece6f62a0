#pragma once
// Geometric verification of a loop candidate with metric depth: the current keyframe's keypoints that
// have depth (3-D points in its camera) are matched by descriptor to the landmarks of the candidate
// keyframe and its best covisible neighbours (3-D points in the map), a 3-point RANSAC finds the rigid
// motion that aligns them (SE(3): depth is metric, no scale; then again among the matches each motion
// leaves out, up to max_motions, since a car driving on with the camera is a rigid motion too, and the
// motion that explains most of the region after the steps below wins), the pose of the current
// keyframe in the candidate's map is refined on that consensus, every region landmark is searched near
// where that pose projects it (guided search), and the pose is refined again on reprojection and depth
// of all the guided matches. A loop is the relative pose between the two keyframes; it is only a loop
// when enough matches agree, and a false loop is worse than none, so every threshold errs on the side
// of rejecting.

#include "rgbl/backend/loop_correction.hpp"
#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"

#include <cstdint>
#include <optional>

namespace rgbl {

struct LoopVerificationOptions {
  std::size_t neighbours = 5;   // best covisible keyframes of the candidate whose landmarks join
  int max_hamming = 50;         // descriptor distance of a match
  // best < ratio * the best among landmarks farther than the agreement tolerance from the best one (a
  // loop is matched without a pose prior; two copies of one point are not an ambiguity)
  float ratio = 0.75F;
  int ransac_iterations = 300;
  std::uint32_t seed = 1;       // fixed: the same map gives the same answer
  // A match agrees with a motion within max(min_tolerance, relative_tolerance * z) m in 3-D.
  double min_tolerance = 0.15;
  double relative_tolerance = 0.02;
  int min_ransac_inliers = 30;
  int min_inliers = 40;         // after pose refinement (ORB-SLAM asks 40 for a loop, with a Sim3)
  double min_inlier_ratio = 0.3;  // of the matches: a few agreeing among many random ones is chance
  // verify_loop_guided: landmarks are searched this far from where the guess projects them, times the
  // scale of the pyramid level their distance predicts (ORB-SLAM's projection searches use 7.5-15 px).
  double guided_radius_px = 10.0;
  // Rigid motions weighed: RANSAC's best, then the best of the matches each leaves out, while one
  // finds min_ransac_inliers. A car driving on with the camera is a motion of its own, and two cars can
  // each outnumber the street among the descriptor matches; the motion that explains most of the
  // region once searched wins.
  int max_motions = 3;

  void validate() const;
};

// How far a candidate got: also filled for a rejected one (the reason is the first count below its
// threshold; 0 after it: not reached).
struct LoopVerificationCounts {
  int matches = 0;         // descriptor matches
  int ransac_inliers = 0;  // agreeing with the best 3-point motion (after refitting on its consensus)
  int guided_matches = 0;  // found by the guided search from the refined pose
  int inliers = 0;         // of the guided matches after the final refinement
};

struct LoopVerification {
  LoopConstraint constraint;  // T_current_matched measured through the matched landmarks
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();  // current keyframe in the candidate's map
  LoopVerificationCounts counts;
};

// `camera` is the current keyframe's. `current` is a keyframe, possibly of another map (merging): only
// its keypoints, descriptors and depths are used, not its pose or landmarks. `candidate` is a keyframe of
// `map`. nullopt: not verified; `counts` (optional) says how far it got. Throws ConfigError on bad
// options and on a current keyframe whose descriptors or depths do not match its keypoints. Read-only on the map: the caller holds its lock (shared is enough).
std::optional<LoopVerification> verify_loop(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                            KeyframeId candidate, const LoopVerificationOptions& options = {},
                                            LoopVerificationCounts* counts = nullptr);

// The same decision from a pose guess instead of descriptor matching alone: the landmarks of the
// candidate and its neighbours are projected with T_cam_world_guess (the current keyframe in the
// candidate's map) and matched to keypoints near them (max_hamming, no ratio test: the guess
// disambiguates), the pose is refined from the guess, searched again from the refined pose and refined
// once more (keypoints without depth count by reprojection). For a keyframe next to one already
// verified, whose pose in the candidate's map follows from it. `counts.ransac_inliers` stays 0 (no
// RANSAC).
std::optional<LoopVerification> verify_loop_guided(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                                   KeyframeId candidate, const Eigen::Isometry3d& T_cam_world_guess,
                                                   const LoopVerificationOptions& options = {},
                                                   LoopVerificationCounts* counts = nullptr);

}  // namespace rgbl
