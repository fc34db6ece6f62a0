#pragma once
// Frame-to-frame rigid motion from depth on both sides: the tracker's prediction before guided
// matching, usable on its own for RGB-D visual odometry between two frames.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/options.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <optional>
#include <span>
#include <vector>

namespace rgbl {

// Two motions T_cur_last judged on what depth cannot hold: `last`'s keypoints without depth, matched to
// `frame` by descriptor (nearest neighbour, ratio 0.8, Hamming <= max_hamming). A match fits a motion
// when its keypoint in `frame` lies within 2 px x scale_factor^level (the pyramid's) of the image of its ray in `last`, from
// 2 m + 1.5 |t| ahead (nearer, the LiDAR would have given it depth) to infinity. Far points fit every
// translation; a car standing still and one driving differ on the points in between (facades, trees
// above the LiDAR's field of view). Each motion's count is of the matches that fit it alone.
struct RayFits {
  int matches = 0;  // brute-force matches tested
  int a_only = 0;
  int b_only = 0;
};
RayFits fits_by_rays(const PinholeCamera& camera, const Frame& last, const Frame& frame, const Eigen::Isometry3d& T_a,
                     const Eigen::Isometry3d& T_b, int max_hamming, double scale_factor);

// T_cur_last (maps points of `last`'s camera into `frame`'s) from brute-force matches (ratio test)
// between keypoints with usable depth and a 3-point RANSAC on their 3-D alignment (Umeyama), refined
// on the consensus. Uses options.ransac_*: a strided subset of at most ransac_max_points current
// keypoints (ransac_max_points_near_prior with a prior), Hamming <= ransac_max_hamming, ratio
// ransac_ratio, ransac_iterations samples (fixed seed: deterministic), a point agrees within
// max(ransac_min_tolerance, ransac_relative_tolerance * z).
//
// With a prior (the constant-velocity motion, when trusted) only motions near it count: translation
// within ransac_prior_translation + ransac_prior_relative * |prior translation| and rotation within
// ransac_prior_rotation_deg. The prior itself, refined on its own consensus, is the first candidate,
// so a static scene outnumbered by an object moving with the camera is still found.
// With ransac_max_points_near_prior_retry above that subset's size (opt-in), a prior, and too few
// agreeing, the RANSAC runs once more on a subset of up to that many.
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

// Marks the points (camera frame, y down) on the dominant ground plane: a plane below the camera by at
// least ground_min_height whose normal is within ground_max_tilt_deg of the camera's vertical, fitted by
// a fixed-seed RANSAC. Empty when no such plane holds ground_min_points points.
std::vector<bool> ground_points(std::span<const Eigen::Vector3d> points, const TrackerOptions& options);

// The returns of a frame's scan sample that can tell two poses of it apart (see scan_arbitration):
// those off the ground plane (the road looks the same under any motion along it, and its scan rings
// coincide best at zero motion), one per scan_sample.tolerance voxel (a truck alongside returns a
// hundred times more points per square metre than a facade across the street).
ScanSample scan_evidence(const ScanSample& sample, const TrackerOptions& options);

// The road in a frame's scan sample (camera frame): the plane n . x = d of ground_points' RANSAC
// (n pointing down, as the camera's y; d the camera's height above it), refitted by least squares to
// its returns. nullopt without one.
struct RoadPlane {
  Eigen::Vector3d n = Eigen::Vector3d::UnitY();
  double d = 0.0;
  int points = 0;  // the returns it was fitted to
};
std::optional<RoadPlane> road_plane(const ScanSample& sample, const TrackerOptions& options);

// Per keypoint of `frame`: with depth and on the dominant ground plane (options.ground_*, the plane
// estimate_frame_motion ranks a consensus by). Empty when no such plane holds ground_min_points.
std::vector<bool> ground_keypoints(const PinholeCamera& camera, const Frame& frame, const TrackerOptions& options);

// A second rigid motion among the matches (see `rival` below).
struct RivalMotion {
  Eigen::Isometry3d T_cur_last = Eigen::Isometry3d::Identity();
  std::vector<bool> moving;  // as `moving`, against this motion
  std::size_t inliers = 0;
};

// With `rival` given, no prior and a motion found: the best consensus of at least
// ransac_min_inliers among the matches the winner leaves out (a second RANSAC on them), if any.
// Without a prior the largest rigid consensus may be an object moving with the camera (a car ahead at
// the ego speed keeps its look while the scene's matches fade with distance travelled), so the caller
// should let other evidence (the local map) choose between the two.
std::optional<Eigen::Isometry3d> estimate_frame_motion(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                       const TrackerOptions& options,
                                                       const std::optional<Eigen::Isometry3d>& prior = std::nullopt,
                                                       std::vector<bool>* moving = nullptr,
                                                       std::optional<RivalMotion>* rival = nullptr);

// T_cur_last from the keypoints on the road (ground_keypoints) of both frames alone: the depth RANSAC
// without a prior, at ransac_guess_min_inliers. The road does not move; a start for a frame without a
// velocity where vehicles hold most of the other matches (TrackerOptions::road_start).
std::optional<Eigen::Isometry3d> estimate_road_motion(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                      const TrackerOptions& options);

}  // namespace rgbl
