#pragma once
// The paper's inverse dilation written the straightforward OpenCV way (SPEC section 3): invert valid
// depths with M - d, zero the pixels that became M (the empty ones), grey-dilate with the structuring
// element, invert back and zero again. Used as the benchmark baseline and as the exactness oracle.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace rgbl::reference {

inline void inverse_dilation(const cv::Mat& sparse, const cv::Mat& element, float max_depth, cv::Mat& dense) {
  const double below_max = std::nextafter(max_depth, 0.0F);
  cv::Mat inverted;
  cv::subtract(cv::Scalar(max_depth), sparse, inverted);
  cv::threshold(inverted, inverted, below_max, 0.0, cv::THRESH_TOZERO_INV);
  cv::dilate(inverted, dense, element);
  cv::subtract(cv::Scalar(max_depth), dense, dense);
  cv::threshold(dense, dense, below_max, 0.0, cv::THRESH_TOZERO_INV);
}

}  // namespace rgbl::reference
