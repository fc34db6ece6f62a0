#pragma once
// The occlusion filter written the straightforward way: for every sample, the nearest sample in the
// (2 radius + 1)^2 square around it, read pixel by pixel; the sample goes when it is more than `ratio`
// times as far. Used as the benchmark baseline and as the exactness oracle of remove_occluded_samples.

#include <opencv2/core.hpp>

#include <algorithm>

namespace rgbl::reference {

inline int remove_occluded_samples(cv::Mat_<float>& sparse, int radius, float ratio) {
  const cv::Mat_<float> before = sparse.clone();
  int dropped = 0;
  for (int v = 0; v < before.rows; ++v) {
    for (int u = 0; u < before.cols; ++u) {
      const float depth = before(v, u);
      if (depth <= 0.0F) continue;
      float nearest = depth;
      for (int y = std::max(0, v - radius); y <= std::min(before.rows - 1, v + radius); ++y) {
        for (int x = std::max(0, u - radius); x <= std::min(before.cols - 1, u + radius); ++x) {
          if (before(y, x) > 0.0F) nearest = std::min(nearest, before(y, x));
        }
      }
      if (depth > ratio * nearest) {
        sparse(v, u) = 0.0F;
        ++dropped;
      }
    }
  }
  return dropped;
}

}  // namespace rgbl::reference
