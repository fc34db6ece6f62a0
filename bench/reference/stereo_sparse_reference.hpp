#pragma once
// Sparse stereo the straightforward way, as the benchmark baseline for `stereo_sparse`: for each
// keypoint, the SAD of an 11x11 window at every disparity in [0, max_disparity] at full resolution
// (window loop innermost), the same texture and uniqueness tests, a parabola through the three costs
// around the minimum. No pyramid, no candidate-parallel cost accumulation.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

namespace rgbl::reference {

// Depth (metres, 0 = none) at each pixel; left/right are CV_8UC1 rectified images.
inline void stereo_sparse(const cv::Mat& left, const cv::Mat& right, const std::vector<Eigen::Vector2f>& pixels,
                          float fb, int max_disparity, std::vector<float>& depth) {
  constexpr int h = 5;
  constexpr float min_texture = 3.0F, max_mean_sad = 20.0F;
  constexpr int uniqueness_ratio = 10;
  depth.assign(pixels.size(), 0.0F);
  std::vector<int> cost(static_cast<std::size_t>(max_disparity + 1));
  for (std::size_t p = 0; p < pixels.size(); ++p) {
    const int x = static_cast<int>(std::lround(pixels[p].x()));
    const int y = static_cast<int>(std::lround(pixels[p].y()));
    if (y - h < 0 || y + h >= left.rows || x - h < 0 || x + h >= left.cols) continue;
    int gradient = 0;
    for (int j = -h; j <= h; ++j) {
      for (int i = -h; i < h; ++i)
        gradient += std::abs(left.at<std::uint8_t>(y + j, x + i + 1) - left.at<std::uint8_t>(y + j, x + i));
    }
    if (static_cast<float>(gradient) < min_texture * static_cast<float>((2 * h + 1) * 2 * h)) continue;
    const int d_max = std::min(max_disparity, x - h);
    int best = -1;
    for (int d = 0; d <= d_max; ++d) {
      int sad = 0;
      for (int j = -h; j <= h; ++j) {
        for (int i = -h; i <= h; ++i)
          sad += std::abs(left.at<std::uint8_t>(y + j, x + i) - right.at<std::uint8_t>(y + j, x - d + i));
      }
      cost[static_cast<std::size_t>(d)] = sad;
      if (best < 0 || sad < cost[static_cast<std::size_t>(best)]) best = d;
    }
    if (best <= 0 || best >= d_max) continue;
    const int c0 = cost[static_cast<std::size_t>(best)];
    bool unique = true;
    for (int d = 0; d <= d_max && unique; ++d) {
      unique = std::abs(d - best) <= 1 || cost[static_cast<std::size_t>(d)] * (100 - uniqueness_ratio) >= c0 * 100;
    }
    if (!unique || static_cast<float>(c0) > max_mean_sad * (2 * h + 1) * (2 * h + 1)) continue;
    const float lo = static_cast<float>(cost[static_cast<std::size_t>(best - 1)]);
    const float hi = static_cast<float>(cost[static_cast<std::size_t>(best + 1)]);
    const float curvature = lo + hi - 2.0F * static_cast<float>(c0);
    if (curvature <= 0.0F) continue;
    const float d = static_cast<float>(best) + (lo - hi) / (2.0F * curvature);
    if (d >= 1.0F) depth[p] = fb / d;
  }
}

}  // namespace rgbl::reference
