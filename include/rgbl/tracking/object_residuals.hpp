#pragma once
// Objects whose points err together against a pose. A car ahead at about the ego speed moves only a
// little against the scene between frames, so each of its points stays inside the per-point gates
// (the motion gate, the pose optimiser's chi2 test), yet over a few frames its landmarks pull the
// pose along. Its points' residuals all point the same way, though: grouped into objects by depth
// continuity, the mean of an object's whitened residuals is far beyond what its points' independent
// noise allows, while a static object's mean stays near zero.

#include "rgbl/backend/pose_optimizer.hpp"
#include "rgbl/geometry/camera.hpp"

#include <Eigen/Geometry>

#include <span>
#include <vector>

namespace rgbl {

// Two observations with depth are on one object when their pixels are within radius_px and their
// depths within max(min_tolerance, relative_tolerance * depth). The tracker passes the ones its moving
// labels group keypoints by (TrackerOptions::moving_label_radius, the RANSAC's tolerances).
struct ObjectGrouping {
  double radius_px = 0.0;
  double min_tolerance = 0.0;  // m
  double relative_tolerance = 0.0;
};

struct ObjectResidualOptions {
  int min_points = 5;              // smaller groups are left to the per-point tests
  // An object errs together when n |mean whitened residual|^2 (chi2 with 3 dof for independent unit
  // noise) exceeds chi2 times the frame's own overdispersion: the median of that statistic over the
  // frame's objects divided by chi2's median (2.366), at least 1. Residuals of one surface share
  // the completion's and the landmarks' errors, so they scatter more than independent noise; the
  // frame's typical object measures by how much. 16.27: 3 dof at 0.999.
  double chi2 = 16.27;
  int min_objects = 3;             // fewer: no typical object to measure the overdispersion by
  // The pose stands on the rest: objects are flagged only while each holds under this share of the
  // observations with depth, and all flagged together too.
  double max_share = 1.0 / 3.0;

  void validate() const;
};

struct ObjectResiduals {
  std::vector<bool> flagged;      // per observation: on an object that errs together
  int objects = 0;                // tested (at least min_points observations)
  int flagged_objects = 0;
  double overdispersion = 1.0;
};

// Tests the inlier observations with depth (inlier[j], depth > 0; exclude[j] leaves one out, e.g.
// the road, which does not move) at T_cam_world. Residuals as pose_residual's (bounded_depth_error
// likewise). Objects are flagged in order of their statistic, most erring first, while the share
// allows.
ObjectResiduals objects_against_pose(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world,
                                     std::span<const PoseObservation> observations, const std::vector<bool>& inlier,
                                     const std::vector<bool>& exclude, const ObjectGrouping& grouping,
                                     const ObjectResidualOptions& options, bool bounded_depth_error);

}  // namespace rgbl
