#pragma once
// Depth-completion metrics (SPEC section 3) and a ground truth for real data without a depth
// benchmark: neighbouring LiDAR scans placed with ground-truth poses and z-buffered into one frame.

#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/projection.hpp"

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <cstddef>
#include <filesystem>
#include <span>
#include <vector>

namespace rgbl {

// Errors over the pixels where both the prediction and the ground truth have depth (> 0). Missing
// predictions are not errors here: `coverage` says how much of the ground truth was predicted.
struct DepthErrors {
  std::size_t count = 0;   // pixels compared
  double coverage = 0.0;   // count / ground-truth pixels
  double mae = 0.0;        // m
  double rmse = 0.0;       // m
  double imae = 0.0;       // 1/km, on inverse depth
  double irmse = 0.0;      // 1/km
};

// Pools pixels over any number of frames (every compared pixel weighs the same).
class DepthErrorAccumulator {
 public:
  // prediction and ground_truth: same size, metres, 0 = none.
  void add(const cv::Mat_<float>& prediction, const cv::Mat_<float>& ground_truth);
  DepthErrors result() const;

 private:
  std::size_t count_ = 0, ground_truth_count_ = 0;
  double abs_sum_ = 0.0, sq_sum_ = 0.0, inv_abs_sum_ = 0.0, inv_sq_sum_ = 0.0;
};

DepthErrors evaluate_depth(const cv::Mat_<float>& prediction, const cv::Mat_<float>& ground_truth);

struct AccumulationOptions {
  int half_window = 5;           // scans center-k .. center+k (those that exist)
  bool include_center = false;   // false: only neighbours, so the input's own samples are not graded by themselves
  ProjectionOptions projection{};

  void validate() const;  // keys accumulation.*
};

// Depth of frame `center` in the camera of `calibration`, from the scans of the neighbouring frames
// placed with T_w_cam0 (ground-truth poses of rectified cam0, one per frame, same indexing as `scans`):
// p_cam = T_cam_cam0 * T_w_cam0[center]^-1 * T_w_cam0[j] * T_cam0_lidar * p_lidar. Nearest point wins.
cv::Mat_<float> accumulate_depth(const CameraCalibration& calibration, std::span<const PointCloudView> scans,
                                 std::span<const Eigen::Isometry3d> T_w_cam0, std::size_t center,
                                 const AccumulationOptions& options = {});

}  // namespace rgbl
