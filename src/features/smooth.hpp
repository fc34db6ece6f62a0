#pragma once
// Internal: the Gaussian smoothing BRIEF samples, 7x7 with sigma 2, as OpenCV computes it for 8-bit
// images (a fixed-point kernel with 8 fraction bits, taps 18 34 48 56 48 34 18, one rounding at the
// end, BORDER_REFLECT_101), to the bit, in 16-bit lanes. Other sizes and sigmas, and images too small
// for it, go to cv::GaussianBlur.

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <vector>

namespace rgbl::detail {

// dst = cv::GaussianBlur(src, (size, size), sigma, sigma, BORDER_REFLECT_101) for CV_8UC1 `src`.
// `padded` and `rows` are scratch kept between calls (a padded source row, the row passes of 8
// rows). `allow_fast = false` always calls OpenCV, for tests.
void smooth_for_brief(const cv::Mat& src, cv::Mat& dst, int size, double sigma, std::vector<std::uint8_t>& padded,
                      std::vector<std::uint16_t>& rows, bool allow_fast = true);

}  // namespace rgbl::detail
