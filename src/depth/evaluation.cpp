#include "rgbl/depth/evaluation.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace rgbl {

void DepthErrorAccumulator::add(const cv::Mat_<float>& prediction, const cv::Mat_<float>& ground_truth) {
  CV_Assert(prediction.size() == ground_truth.size());
  for (int y = 0; y < ground_truth.rows; ++y) {
    const float* gt = ground_truth[y];
    const float* pred = prediction[y];
    for (int x = 0; x < ground_truth.cols; ++x) {
      if (!(gt[x] > 0.0F)) continue;
      ++ground_truth_count_;
      if (!(pred[x] > 0.0F)) continue;
      ++count_;
      const double error = static_cast<double>(pred[x]) - static_cast<double>(gt[x]);
      const double inverse_error = 1000.0 / static_cast<double>(pred[x]) - 1000.0 / static_cast<double>(gt[x]);
      abs_sum_ += std::abs(error);
      sq_sum_ += error * error;
      inv_abs_sum_ += std::abs(inverse_error);
      inv_sq_sum_ += inverse_error * inverse_error;
    }
  }
}

DepthErrors DepthErrorAccumulator::result() const {
  DepthErrors e;
  e.count = count_;
  if (ground_truth_count_ > 0) e.coverage = static_cast<double>(count_) / static_cast<double>(ground_truth_count_);
  if (count_ == 0) return e;
  const auto n = static_cast<double>(count_);
  e.mae = abs_sum_ / n;
  e.rmse = std::sqrt(sq_sum_ / n);
  e.imae = inv_abs_sum_ / n;
  e.irmse = std::sqrt(inv_sq_sum_ / n);
  return e;
}

DepthErrors evaluate_depth(const cv::Mat_<float>& prediction, const cv::Mat_<float>& ground_truth) {
  DepthErrorAccumulator accumulator;
  accumulator.add(prediction, ground_truth);
  return accumulator.result();
}

void AccumulationOptions::validate() const {
  require(half_window >= 0, "accumulation.half_window", "a number of frames >= 0");
  require(half_window > 0 || include_center, "accumulation.include_center",
          "true when accumulation.half_window is 0 (otherwise no scan is used)");
  projection.validate();
}

cv::Mat_<float> accumulate_depth(const CameraCalibration& calibration, std::span<const PointCloudView> scans,
                                 std::span<const Eigen::Isometry3d> T_w_cam0, std::size_t center,
                                 const AccumulationOptions& options) {
  options.validate();
  require(scans.size() == T_w_cam0.size(), "accumulation.poses", "one pose per scan");
  require(center < scans.size(), "accumulation.center", "a frame index inside the sequence");
  const PinholeCamera& camera = calibration.camera;
  const Eigen::Isometry3d T_cam0_lidar = calibration.T_cam_cam0.inverse() * calibration.T_cam_lidar;
  const Eigen::Isometry3d T_cam_w = calibration.T_cam_cam0 * T_w_cam0[center].inverse();
  cv::Mat_<float> merged(camera.height, camera.width, 0.0F);
  cv::Mat_<float> single(camera.height, camera.width);
  const auto k = static_cast<std::size_t>(options.half_window);
  const std::size_t first = center >= k ? center - k : 0;
  const std::size_t last = std::min(scans.size() - 1, center + k);
  for (std::size_t j = first; j <= last; ++j) {
    if (j == center && !options.include_center) continue;
    const Eigen::Isometry3d T_cam_lidar_j = T_cam_w * T_w_cam0[j] * T_cam0_lidar;
    const Matrix34d P = camera.K() * to_3x4(T_cam_lidar_j);
    project_to_depth(scans[j], P, options.projection, single);
    for (int y = 0; y < merged.rows; ++y) {
      float* out = merged[y];
      const float* in = single[y];
      for (int x = 0; x < merged.cols; ++x) {
        if (in[x] > 0.0F && (out[x] == 0.0F || in[x] < out[x])) out[x] = in[x];
      }
    }
  }
  return merged;
}

}  // namespace rgbl
