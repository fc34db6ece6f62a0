#pragma once
// Frame-to-frame rigid motion from depth on both sides: the tracker's prediction before guided
// matching, usable on its own for RGB-D visual odometry between two frames.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/options.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <optional>

namespace rgbl {

// T_cur_last (maps points of `last`'s camera into `frame`'s) from brute-force matches (ratio test)
// between keypoints with usable depth and a 3-point RANSAC on their 3-D alignment (Umeyama), refined
// on the consensus. Uses options.ransac_*: a strided subset of at most ransac_max_points current
// keypoints, Hamming <= ransac_max_hamming, ratio ransac_ratio, ransac_iterations samples (fixed seed:
// deterministic), a point agrees within max(ransac_min_tolerance, ransac_relative_tolerance * z).
//
// With a prior (the constant-velocity motion, when trusted) only motions near it count: translation
// within ransac_prior_translation + ransac_prior_relative * |prior translation| and rotation within
// ransac_prior_rotation_deg. The prior itself, refined on its own consensus, is the first candidate,
// so a static scene outnumbered by an object moving with the camera is still found.
// nullopt: fewer than ransac_min_inliers agree (then the caller keeps its own prediction).
//
// With `moving` given and a motion found, it is set per keypoint of `frame`: matched points further
// than motion_gate_factor tolerances from the motion, and keypoints with depth within
// moving_label_radius px of such a point at a continuous depth (nearer to it than to a point that
// agrees), are on something moving against the scene.
// How far a point at depth z may be from where a rigid motion puts it and still agree with it:
// max(ransac_min_tolerance, ransac_relative_tolerance * z), LiDAR noise growing with range.
inline double depth_tolerance(double z, const TrackerOptions& options) {
  return std::max(options.ransac_min_tolerance, options.ransac_relative_tolerance * z);
}

std::optional<Eigen::Isometry3d> estimate_frame_motion(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                       const TrackerOptions& options,
                                                       const std::optional<Eigen::Isometry3d>& prior = std::nullopt,
                                                       std::vector<bool>* moving = nullptr);

}  // namespace rgbl
