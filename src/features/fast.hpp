#pragma once
// Internal: FAST-9 (9 contiguous pixels of the 16-pixel circle of radius 3) corner scores and 3x3
// non-maximum suppression, written for one pass per pyramid level at the lowest threshold.

#include "rgbl/features/orb.hpp"
#include "simd.hpp"

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <vector>

namespace rgbl::detail {

// FastCorner (rgbl/features/orb.hpp): score = largest threshold t at which the pixel is a corner
// (p > c + t or p < c - t on a 9-arc).

// Score map over `region` (every pixel of it must be >= 3 px inside `img`): score[(y - region.y + 1)
// * (region.width + 2) + (x - region.x + 1)] is the pixel's FAST score if it is a corner at
// `threshold`, else 0. The map has a ring of zeros around the region (width + 2 by height + 2).
// `widest` caps the vector width, for tests (here and in detect_fast): by default CPUs with AVX-512BW
// score and suppress 64 pixels a step, with AVX2 32, else SSE2 16.
void fast_score_map(const cv::Mat& img, cv::Rect region, int threshold, std::vector<std::uint8_t>& scores,
                    SimdWidth widest = SimdWidth::avx512);

// Corners of `region` at `threshold` that are maxima of their 3x3 neighbourhood (ties: the first in
// row-major order wins), in row-major order. `scores` is scratch.
void detect_fast(const cv::Mat& img, cv::Rect region, int threshold, std::vector<std::uint8_t>& scores,
                 std::vector<FastCorner>& corners, SimdWidth widest = SimdWidth::avx512);

}  // namespace rgbl::detail
