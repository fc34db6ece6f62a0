#pragma once
// One frame of a dataset as the loaders deliver it: owning, so it can travel between threads.

#include "rgbl/geometry/point_cloud.hpp"

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

namespace rgbl {

struct FrameInput {
  std::size_t index = 0;
  double timestamp = 0.0;  // seconds, as the dataset gives it
  // Rectified images; empty when the camera is absent or was not requested. KITTI: 0/1 are the grey
  // stereo pair (CV_8UC1), 2/3 the colour pair (CV_8UC3, BGR). TUM: the RGB camera is 2 (colour) and
  // 0 (its grey conversion).
  std::array<cv::Mat, 4> images;
  cv::Mat_<float> depth;                          // depth camera (TUM), metres, 0 = none; empty if none
  std::vector<LidarPoint> scan;                   // LiDAR frame; empty if none
  std::optional<double> scan_timestamp;           // when the scan faced forward (KITTI raw), same clock
  std::optional<Eigen::Isometry3d> T_world_cam0;  // ground truth, when the dataset has it

  const cv::Mat& grey_left() const { return images[0]; }
  const cv::Mat& grey_right() const { return images[1]; }
  const cv::Mat& colour_left() const { return images[2]; }
  const cv::Mat& colour_right() const { return images[3]; }
};

}  // namespace rgbl
