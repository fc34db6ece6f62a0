#pragma once
// Local bundle adjustment on Ceres (private to this module): keyframe poses and landmark positions
// with reprojection and depth residuals, Huber loss, Schur elimination, some poses held fixed, and an
// abort flag that stops the solve between iterations.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/se3.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <atomic>
#include <vector>

namespace rgbl {

struct BundlePose {
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  bool fixed = false;
};

struct BundleObservation {
  int pose = 0;      // index into BundleProblem::poses
  int point = 0;     // index into BundleProblem::points
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  double sigma_px = 1.0;
  double depth = 0.0;        // 0 = reprojection only
  double depth_sigma = 0.0;
};

// Two poses that see one plane (the road under a car, in their LiDAR scans): plane_a and plane_b,
// (n, d) of n . x = d in each camera frame, must be the same plane in the world. Three residuals in
// b's frame: the tilt between b's plane and a's seen from b (2, whitened by sigma_tilt, rad) and the
// offset (m, by sigma_offset), Huber-robust like a depth observation.
struct BundlePlanePair {
  int pose_a = 0, pose_b = 0;
  Eigen::Vector4d plane_a = Eigen::Vector4d::UnitY(), plane_b = Eigen::Vector4d::UnitY();
  double sigma_tilt = 0.01, sigma_offset = 0.05;
};
// The motion tracking measured between two poses: T_b_a = T_cam_b_world * inv(T_cam_a_world). Six
// residuals of E = inv(T_b_a) * T_b * inv(T_a) in b's frame: its translation (m, by sigma_translation)
// and rotation angle-vector (rad, by sigma_rotation); Huber at 3.55 (95 % of chi2, 6 dof). level_only
// keeps the three a road pair does not see: translation along b's x and z axes and rotation about
// its y axis (down).
struct BundlePosePair {
  int pose_a = 0, pose_b = 0;
  Eigen::Isometry3d T_b_a = Eigen::Isometry3d::Identity();
  double sigma_translation = 0.05, sigma_rotation = 0.005;
  bool level_only = false;
};

struct BundleProblem {
  std::vector<BundlePose> poses;
  std::vector<Eigen::Vector3d> points;
  std::vector<BundleObservation> observations;
  std::vector<BundlePlanePair> plane_pairs;  // only between poses that have observations
  std::vector<BundlePosePair> pose_pairs;    // only between poses that have observations
};

struct BundleAdjustmentOptions {
  int iterations = 10;
  double chi2_2d = 5.991, chi2_3d = 7.815;  // Huber thresholds and outlier tests
  bool dense_schur = true;   // DENSE_SCHUR (small local windows) or SPARSE_SCHUR
  int threads = 1;

  void validate() const;
};

struct BundleAdjustmentResult {
  std::vector<bool> outlier;  // per observation, chi2 above the threshold after the solve
  int iterations = 0;
  bool aborted = false;
  double initial_cost = 0.0, final_cost = 0.0;
};

// Optimises problem.poses (non-fixed) and problem.points in place.
BundleAdjustmentResult bundle_adjust(const PinholeCamera& camera, BundleProblem& problem,
                                     const BundleAdjustmentOptions& options = {},
                                     const std::atomic<bool>* abort = nullptr);

// The residual bundle_adjust minimises for one observation, evaluated through the same Ceres cost
// function, with Jacobians w.r.t. the pose parameters [angle-axis(3), translation(3)] of T_cam_world
// and the point: for tests against numeric differentiation. Returns the residual dimension (2 or 3).
int bundle_residual(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world, const Eigen::Vector3d& point,
                    const BundleObservation& observation, Eigen::Vector3d& residual,
                    Eigen::Matrix<double, 3, 6>& d_pose, Eigen::Matrix3d& d_point);

// The pose parameterisation bundle_residual differentiates by.
Vector6d pose_to_parameters(const Eigen::Isometry3d& T);
Eigen::Isometry3d parameters_to_pose(const Vector6d& parameters);

}  // namespace rgbl
