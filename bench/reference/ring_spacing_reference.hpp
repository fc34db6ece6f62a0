#pragma once
// The LiDAR rings' spacing in a sparse depth image, measured the straightforward way: every band of 3
// columns, walked top to bottom, every gap of more than one row collected, the median by sorting.
// rgbl::ring_spacing_px reads about 26 bands across the image (one in 16 on KITTI's 1226 px), row by row. The benchmark baseline, and a check that
// the sampled bands give the same median on a real scan.

#include <opencv2/core.hpp>

#include <algorithm>
#include <optional>
#include <vector>

namespace rgbl::reference {

inline std::optional<double> ring_spacing_px(const cv::Mat_<float>& sparse) {
  std::vector<int> gaps;
  for (int c = 0; c + 3 <= sparse.cols; c += 3) {
    int last = -1;
    for (int r = 0; r < sparse.rows; ++r) {
      if (!(sparse(r, c) > 0.0F || sparse(r, c + 1) > 0.0F || sparse(r, c + 2) > 0.0F)) continue;
      if (last >= 0 && r - last > 1) gaps.push_back(r - last);
      last = r;
    }
  }
  if (gaps.empty()) return std::nullopt;
  std::sort(gaps.begin(), gaps.end());
  return static_cast<double>(gaps[gaps.size() / 2]);
}

}  // namespace rgbl::reference
