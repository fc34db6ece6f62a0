#pragma once
// Pose-only optimisation of one camera against known 3-D points: a hand-written Gauss-Newton on SE(3)
// with analytic Jacobians (a per-frame Ceres solve costs more in overhead than the whole problem),
// Huber weights and rounds of outlier re-classification as in ORB-SLAM.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/se3.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <vector>

namespace rgbl {

// One 2-D (and optionally depth) measurement of a known world point.
struct PoseObservation {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  double sigma_px = 1.0;     // pixel standard deviation (ORB: scale factor ^ level)
  double depth = 0.0;        // measured camera z, metres; 0 = 2-D observation only
  double depth_sigma = 0.0;  // metres; used when depth > 0
};

struct PoseOptimizerOptions {
  int rounds = 4;              // outlier re-classification rounds
  int iterations = 10;         // Gauss-Newton iterations per round
  double chi2_2d = 5.991;      // 95% of chi2 with 2 dof
  double chi2_3d = 7.815;      // 95% of chi2 with 3 dof
  bool robust_last_round = false;  // ORB-SLAM drops the robust kernel in the last rounds
  // Huber's influence never vanishes: points that err together (a car ahead at about the camera's
  // speed, a repeated pattern matched one period off) pull the pose their way, and the outlier rounds
  // then keep them. With cauchy the rounds after the first weigh a residual by 1 / (1 + e^2 / c^2), c^2
  // the chi2 threshold, so their influence fades. The first round stays Huber's: from a start off the
  // pose (a gap, a relocalisation) fading weights can settle on whichever consensus is nearest, e.g. a
  // repeated street one period short (docs/accuracy.md, "Cauchy weights after a Huber round").
  bool cauchy = false;
  double min_depth = 1e-3;     // points closer than this to the camera plane are outliers
  // The depth error beyond the measured depth d as (z - d) d / z (bounded by d as z grows, as ORB-SLAM's
  // disparity error is) instead of z - d; nearer than d it is z - d either way. It fixes the
  // relocalisation of docs/accuracy.md ("Keyframes when all the reference's landmarks thin out").
  // The tracker turns it on (TrackerOptions::pose); off here for the other callers.
  bool bounded_depth_error = false;

  void validate() const;
};

// A car moves along its heading: between two frames its camera's centre moves along the car's direction
// of travel, which in the camera's own frame is fixed by the mount (yaw and pitch against the car's
// axis). Across it the centre moves only by the body's sway on its springs, by the pitch under braking
// or on a change of slope, and in a turn by the camera's lever ahead of the rear axle. A soft prior on
// the step across that direction, none along it (braking, gaps and standing still stay free): crossing
// traffic or a group of matches on a vehicle can pull a pose sideways or up, which no car does.
// Across the direction, sigma = floor_m + per_m * |step along| + lever_m * turn (rad).
struct MotionPriorSigmas {
  double floor_m = 0.01;  // the body's sway: roll or pitch of ~0.5 deg at 1-1.5 m above the axle
  double per_m = 0.035;   // 2 deg: pitch under braking or on a crest, and the direction's own error
  double lever_m = 2.0;   // a camera up to 2 m ahead of the rear axle slides out by that times the turn

  void validate() const;
};

struct PoseMotionPrior {
  Eigen::Isometry3d T_last_world = Eigen::Isometry3d::Identity();  // the previous frame's pose
  Eigen::Vector3d direction_cam = Eigen::Vector3d::UnitZ();  // unit; in the camera frame half-way through the turn
  MotionPriorSigmas sigmas;
};

// The step from T_last_world's camera centre to T_cur_world's, in the camera frame turned half-way
// between the two (so that a step along an arc reads as straight ahead); the direction a
// PoseMotionPrior is learned from.
Eigen::Vector3d step_in_mid_frame(const Eigen::Isometry3d& T_last_world, const Eigen::Isometry3d& T_cur_world);

// Whitened residual of a PoseMotionPrior at T_cam_world (2 entries across the direction) and its
// Jacobian for the left perturbation of pose_residual (the direction and sigma held at T_cam_world).
void motion_prior_residual(const PoseMotionPrior& prior, const Eigen::Isometry3d& T_cam_world,
                           Eigen::Vector2d& residual, Eigen::Matrix<double, 2, 6>& jacobian);

struct PoseOptimizerResult {
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  std::vector<bool> inlier;    // per observation
  int inliers = 0;
  double final_chi2 = 0.0;     // sum over inliers
};

// Residual of one observation at pose T_cam_world, whitened by its sigmas: 2 or 3 entries
// (u, v, then the depth error when the observation has depth: z - d, or with bounded_depth_error
// (z - d) min(1, d / z), metric up to the measured depth d and bounded by d for a point far beyond it).
// jacobian (rows as residual) is with respect to a left perturbation T <- exp(xi) * T, xi = [rho; phi].
// Returns false when the point is behind.
bool pose_residual(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world, const PoseObservation& obs,
                   Eigen::Vector3d& residual, Eigen::Matrix<double, 3, 6>& jacobian, int& dimension,
                   bool bounded_depth_error = false);

// Distortion of the camera is ignored: keypoints are expected in rectified, undistorted images.
// With a motion prior, it is added to every iteration (it never counts as an inlier nor in final_chi2).
PoseOptimizerResult optimize_pose(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world_initial,
                                  std::span<const PoseObservation> observations,
                                  const PoseOptimizerOptions& options = {},
                                  const std::optional<PoseMotionPrior>& motion_prior = std::nullopt);

}  // namespace rgbl
