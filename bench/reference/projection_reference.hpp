#pragma once
// The projection as the public RGB-L reference code does it, kept as the benchmark baseline (our own
// code, written to the same recipe): the scan as a 4xN CV_32F matrix, one cv::Mat product with the
// 3x4 projection, row-wise normalisation by z, then a per-point loop writing into the image with
// truncated (not rounded) coordinates, so that the last point in scan order wins, not the nearest.
// Not for use: see rgbl::project_to_depth.

#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/se3.hpp"

#include <opencv2/core.hpp>

namespace rgbl::reference {

// The 4xN homogeneous matrix the reference keeps its scans in (prepared once per scan, untimed).
inline cv::Mat to_homogeneous_matrix(PointCloudView cloud) {
  cv::Mat X(4, static_cast<int>(cloud.size()), CV_32F);
  for (int i = 0; i < X.cols; ++i) {
    const auto& p = cloud[static_cast<std::size_t>(i)];
    X.at<float>(0, i) = p.x;
    X.at<float>(1, i) = p.y;
    X.at<float>(2, i) = p.z;
    X.at<float>(3, i) = 1.0F;
  }
  return X;
}

inline void project_to_depth(const cv::Mat& X, const Matrix34d& P_img_lidar, float min_depth, float max_depth,
                             cv::Mat& depth) {
  cv::Mat P(3, 4, CV_32F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) P.at<float>(r, c) = static_cast<float>(P_img_lidar(r, c));
  depth = cv::Mat::zeros(depth.size(), CV_32F);
  cv::Mat x = P * X;
  x.row(0) = x.row(0).mul(1.0 / x.row(2));
  x.row(1) = x.row(1).mul(1.0 / x.row(2));
  for (int i = 0; i < x.cols; ++i) {
    const float u = x.at<float>(0, i);
    const float v = x.at<float>(1, i);
    const float z = x.at<float>(2, i);
    if (u > 0 && v > 0 && u < static_cast<float>(depth.cols) && v < static_cast<float>(depth.rows) &&
        z > min_depth && z < max_depth) {
      depth.at<float>(static_cast<int>(v), static_cast<int>(u)) = z;
    }
  }
}

}  // namespace rgbl::reference
