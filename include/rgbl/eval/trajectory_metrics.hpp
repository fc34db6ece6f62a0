#pragma once
// Trajectory accuracy metrics. Every function takes the estimate and the ground truth as equally long
// lists of T_world_cam poses for the same frames (associate by timestamp first where needed), and
// throws rgbl::Error when the lengths differ.
//
// - KITTI odometry metric (the devkit's definition, SPEC section 6): for every step_size-th start
//   frame f and every length L, the first frame l whose ground-truth path distance exceeds
//   dist(f) + L; error pose E = inv(inv(Pe_f) Pe_l) * (inv(Pg_f) Pg_l); t_err = |t_E| / L,
//   r_err = angle(R_E) / L. Averaged over all segments (and per length).
// - ATE: RMSE of positions after the rigid (SE3, no scale) Umeyama alignment of estimate to truth.
// - RPE per frame: E_i = inv(inv(Pg_i) Pg_{i+d}) * (inv(Pe_i) Pe_{i+d}), |t_E| and angle(R_E).
// - End-point drift: |t| of the error pose between the first and last frame, as % of the path length.

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace rgbl {

struct KittiMetricOptions {
  std::vector<double> lengths{100, 200, 300, 400, 500, 600, 700, 800};  // m; KITTI's
  std::size_t step_size = 10;                                           // frames between start frames

  void validate() const;
};

struct KittiSegmentError {
  std::size_t first_frame = 0;
  double length = 0.0;  // m
  double t_err = 0.0;   // |t_E| / L, ratio
  double r_err = 0.0;   // angle(R_E) / L, rad/m
};

struct KittiLengthError {
  double length = 0.0;
  std::size_t segments = 0;
  double t_err_percent = 0.0;       // NaN when segments == 0
  double r_err_deg_per_100m = 0.0;  // NaN when segments == 0
};

struct KittiMetric {
  std::size_t segments = 0;         // 0 when the run is shorter than the shortest length
  double t_err_percent = 0.0;       // mean over all segments, %; NaN when segments == 0
  double r_err_deg_per_100m = 0.0;  // mean over all segments, deg/100 m; NaN when segments == 0
  std::vector<KittiLengthError> per_length;
  std::vector<KittiSegmentError> segment_errors;
};

// Cumulative path length of the positions, dist[0] = 0.
std::vector<double> trajectory_distances(std::span<const Eigen::Isometry3d> poses);

KittiMetric kitti_metric(std::span<const Eigen::Isometry3d> estimate, std::span<const Eigen::Isometry3d> ground_truth,
                         const KittiMetricOptions& options = {});

struct ErrorStats {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;  // NaN for no samples
};
ErrorStats error_stats(std::span<const double> errors);

struct AteResult {
  ErrorStats translation;                                      // m
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();  // alignment applied to the estimate
  std::vector<double> errors;                                  // per pose, m
};

// align = false compares the positions as given.
AteResult absolute_trajectory_error(std::span<const Eigen::Isometry3d> estimate,
                                    std::span<const Eigen::Isometry3d> ground_truth, bool align = true);

struct RpeResult {
  ErrorStats translation;                                       // m per `delta` frames
  ErrorStats rotation_deg;                                      // deg per `delta` frames
  std::vector<double> translation_errors, rotation_errors_deg;  // per pair (i, i + delta)
};

RpeResult relative_pose_error(std::span<const Eigen::Isometry3d> estimate,
                              std::span<const Eigen::Isometry3d> ground_truth, std::size_t delta = 1);

struct DriftResult {
  double path_length = 0.0;  // m, ground truth
  double end_error = 0.0;    // m
  double percent = 0.0;      // end_error / path_length * 100; NaN for a zero-length path
};

DriftResult end_point_drift(std::span<const Eigen::Isometry3d> estimate,
                            std::span<const Eigen::Isometry3d> ground_truth);

// Segment lengths that suit a path of `path_length` m: KITTI's 100..800 m from 800 m on; a shorter
// path gets up to 8 round lengths below its length (SPEC 6), so that it still has segments. Figures
// with other than KITTI's lengths are not comparable with published ones.
KittiMetricOptions kitti_options_for_path(double path_length);

// "100..800 m", or "10..50 m (short run)" for lengths other than KITTI's.
std::string describe_lengths(const KittiMetricOptions& options);

// Every metric above at once, as `rgbl run` and `rgbl eval` report them.
struct TrajectoryEvaluation {
  std::size_t poses = 0;
  double path_length = 0.0;  // m, ground truth
  // m, the estimate's own: far below path_length when tracking stood still while the car drove
  double estimated_path_length = 0.0;
  KittiMetricOptions kitti_options;
  KittiMetric kitti;
  AteResult ate;
  RpeResult rpe;  // per frame
  DriftResult drift;
};

// At least 2 poses. The KITTI lengths are kitti_options_for_path(path) unless `kitti` is given.
TrajectoryEvaluation evaluate_trajectory(std::span<const Eigen::Isometry3d> estimate,
                                         std::span<const Eigen::Isometry3d> ground_truth,
                                         const std::optional<KittiMetricOptions>& kitti = std::nullopt);

}  // namespace rgbl
