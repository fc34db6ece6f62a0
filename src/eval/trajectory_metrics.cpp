#include "rgbl/eval/trajectory_metrics.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

namespace rgbl {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

void require_same_length(std::span<const Eigen::Isometry3d> estimate, std::span<const Eigen::Isometry3d> gt) {
  if (estimate.size() != gt.size()) {
    throw Error(
        fmt::format("the estimate has {} poses but the ground truth has {}: they must be for the same "
                    "frames",
                    estimate.size(), gt.size()));
  }
}

// Relative motion from a to b. The full inverse, as the devkit computes it: with rotations read from
// 7-digit files (orthonormal to ~1e-7 only) a transpose-inverse would leave a trace error that
// acos((trace - 1) / 2) turns into ~1e-4 rad of spurious rotation.
Eigen::Isometry3d between(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b) {
  return T_a.inverse(Eigen::Affine) * T_b;
}

// The devkit's rotation error: acos of (trace - 1) / 2, clamped.
double devkit_rotation_angle(const Eigen::Matrix3d& R) {
  const double d = 0.5 * (R(0, 0) + R(1, 1) + R(2, 2) - 1.0);
  return std::acos(std::clamp(d, -1.0, 1.0));
}

}  // namespace

void KittiMetricOptions::validate() const {
  require(!lengths.empty(), "lengths", "at least one segment length");
  for (double L : lengths) require(L > 0.0 && std::isfinite(L), "lengths", "positive segment lengths in metres");
  require(step_size >= 1, "step_size", "at least 1 frame");
}

std::vector<double> trajectory_distances(std::span<const Eigen::Isometry3d> poses) {
  std::vector<double> dist;
  dist.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    dist.push_back(i == 0 ? 0.0 : dist.back() + (poses[i].translation() - poses[i - 1].translation()).norm());
  }
  return dist;
}

KittiMetric kitti_metric(std::span<const Eigen::Isometry3d> estimate, std::span<const Eigen::Isometry3d> ground_truth,
                         const KittiMetricOptions& options) {
  options.validate();
  require_same_length(estimate, ground_truth);
  const auto dist = trajectory_distances(ground_truth);
  KittiMetric metric;
  std::vector<double> t_sum(options.lengths.size(), 0.0), r_sum(options.lengths.size(), 0.0);
  std::vector<std::size_t> n(options.lengths.size(), 0);
  for (std::size_t first = 0; first < ground_truth.size(); first += options.step_size) {
    for (std::size_t k = 0; k < options.lengths.size(); ++k) {
      const double L = options.lengths[k];
      // First frame whose distance exceeds dist[first] + L (the devkit's lastFrameFromSegmentLength).
      const auto it = std::upper_bound(dist.begin() + static_cast<std::ptrdiff_t>(first), dist.end(), dist[first] + L);
      if (it == dist.end()) continue;
      const auto last = static_cast<std::size_t>(it - dist.begin());
      const Eigen::Isometry3d E =
          between(between(estimate[first], estimate[last]), between(ground_truth[first], ground_truth[last]));
      KittiSegmentError s;
      s.first_frame = first;
      s.length = L;
      s.t_err = E.translation().norm() / L;
      s.r_err = devkit_rotation_angle(E.linear()) / L;
      metric.segment_errors.push_back(s);
      t_sum[k] += s.t_err;
      r_sum[k] += s.r_err;
      ++n[k];
    }
  }
  metric.segments = metric.segment_errors.size();
  double t_all = 0.0, r_all = 0.0;
  for (std::size_t k = 0; k < options.lengths.size(); ++k) {
    KittiLengthError e;
    e.length = options.lengths[k];
    e.segments = n[k];
    e.t_err_percent = n[k] == 0 ? kNaN : 100.0 * t_sum[k] / static_cast<double>(n[k]);
    e.r_err_deg_per_100m = n[k] == 0 ? kNaN : 100.0 * kRadToDeg * r_sum[k] / static_cast<double>(n[k]);
    metric.per_length.push_back(e);
    t_all += t_sum[k];
    r_all += r_sum[k];
  }
  const auto count = static_cast<double>(metric.segments);
  metric.t_err_percent = metric.segments == 0 ? kNaN : 100.0 * t_all / count;
  metric.r_err_deg_per_100m = metric.segments == 0 ? kNaN : 100.0 * kRadToDeg * r_all / count;
  return metric;
}

ErrorStats error_stats(std::span<const double> errors) {
  if (errors.empty()) return {kNaN, kNaN, kNaN, kNaN};
  ErrorStats s;
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  const auto n = static_cast<double>(errors.size());
  s.rmse = std::sqrt(sum_sq / n);
  s.mean = sum / n;
  s.max = *std::max_element(errors.begin(), errors.end());
  std::vector<double> sorted(errors.begin(), errors.end());
  std::sort(sorted.begin(), sorted.end());
  const std::size_t mid = sorted.size() / 2;
  s.median = sorted.size() % 2 == 1 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  return s;
}

AteResult absolute_trajectory_error(std::span<const Eigen::Isometry3d> estimate,
                                    std::span<const Eigen::Isometry3d> ground_truth, bool align) {
  require_same_length(estimate, ground_truth);
  AteResult result;
  const auto n = static_cast<Eigen::Index>(estimate.size());
  Eigen::Matrix3Xd p_est(3, n), p_gt(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    p_est.col(i) = estimate[static_cast<std::size_t>(i)].translation();
    p_gt.col(i) = ground_truth[static_cast<std::size_t>(i)].translation();
  }
  if (align && n >= 3) {
    result.T_gt_est.matrix() = Eigen::umeyama(p_est, p_gt, false);
  } else if (align && n >= 1) {
    // Too few points to fix a rotation: align the centroids only.
    result.T_gt_est.translation() = p_gt.rowwise().mean() - p_est.rowwise().mean();
  }
  result.errors.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    result.errors.push_back((result.T_gt_est * Eigen::Vector3d(p_est.col(i)) - p_gt.col(i)).norm());
  }
  result.translation = error_stats(result.errors);
  return result;
}

RpeResult relative_pose_error(std::span<const Eigen::Isometry3d> estimate,
                              std::span<const Eigen::Isometry3d> ground_truth, std::size_t delta) {
  require_same_length(estimate, ground_truth);
  require(delta >= 1, "delta", "at least 1 frame");
  RpeResult result;
  for (std::size_t i = 0; i + delta < estimate.size(); ++i) {
    const Eigen::Isometry3d E =
        between(between(ground_truth[i], ground_truth[i + delta]), between(estimate[i], estimate[i + delta]));
    result.translation_errors.push_back(E.translation().norm());
    result.rotation_errors_deg.push_back(rotation_angle(E.linear()) * kRadToDeg);
  }
  result.translation = error_stats(result.translation_errors);
  result.rotation_deg = error_stats(result.rotation_errors_deg);
  return result;
}

DriftResult end_point_drift(std::span<const Eigen::Isometry3d> estimate,
                            std::span<const Eigen::Isometry3d> ground_truth) {
  require_same_length(estimate, ground_truth);
  DriftResult d;
  if (estimate.size() < 2) {
    d.percent = kNaN;
    return d;
  }
  d.path_length = trajectory_distances(ground_truth).back();
  const Eigen::Isometry3d E =
      between(between(estimate.front(), estimate.back()), between(ground_truth.front(), ground_truth.back()));
  d.end_error = E.translation().norm();
  d.percent = d.path_length > 0.0 ? 100.0 * d.end_error / d.path_length : kNaN;
  return d;
}

KittiMetricOptions kitti_options_for_path(double path_length) {
  KittiMetricOptions options;
  if (path_length >= 800.0) return options;
  const double step = std::max(1.0, std::ceil(path_length / 80.0)) * 10.0;
  options.lengths.clear();
  for (double l = step; l < path_length && options.lengths.size() < 8; l += step) options.lengths.push_back(l);
  if (options.lengths.empty()) options.lengths.push_back(std::max(1.0, std::floor(path_length / 2.0)));
  return options;
}

std::string describe_lengths(const KittiMetricOptions& options) {
  if (options.lengths.empty()) return "no lengths";
  const bool kitti = options.lengths == KittiMetricOptions{}.lengths;
  return fmt::format("{:g}..{:g} m{}", options.lengths.front(), options.lengths.back(), kitti ? "" : " (short run)");
}

TrajectoryEvaluation evaluate_trajectory(std::span<const Eigen::Isometry3d> estimate,
                                         std::span<const Eigen::Isometry3d> ground_truth,
                                         const std::optional<KittiMetricOptions>& kitti) {
  if (estimate.size() != ground_truth.size() || estimate.size() < 2) {
    throw Error(fmt::format("evaluate_trajectory: {} estimated and {} ground-truth poses (expected as many, >= 2)",
                            estimate.size(), ground_truth.size()));
  }
  TrajectoryEvaluation e;
  e.poses = estimate.size();
  e.drift = end_point_drift(estimate, ground_truth);
  e.path_length = e.drift.path_length;
  e.estimated_path_length = trajectory_distances(estimate).back();
  e.kitti_options = kitti ? *kitti : kitti_options_for_path(e.path_length);
  e.kitti = kitti_metric(estimate, ground_truth, e.kitti_options);
  e.ate = absolute_trajectory_error(estimate, ground_truth);
  e.rpe = relative_pose_error(estimate, ground_truth, 1);
  return e;
}

}  // namespace rgbl
