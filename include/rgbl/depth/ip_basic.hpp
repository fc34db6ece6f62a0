#pragma once
// IP-Basic (Ku et al., 2018), the classical depth-completion anchor, written from its published
// description (SPEC section 3) with OpenCV imgproc. Much denser than one inverse dilation, and slower.

#include <opencv2/core/mat.hpp>

namespace rgbl {

enum class IpBasicBlur { bilateral, gaussian };

struct IpBasicOptions {
  float max_depth = 100.0F;   // inversion constant; depths at or beyond it are dropped
  bool extrapolate = false;   // extend each column's top-most depth to the image top, fill with 31x31
  IpBasicBlur blur = IpBasicBlur::bilateral;
  float near_depth = 15.0F;   // multiscale bins: near < near_depth <= mid < far_depth <= far
  float far_depth = 30.0F;

  void validate() const;  // keys ip_basic.*
};

// "fast": diamond 5x5 dilation, 5x5 closing, 7x7 hole fill, [extrapolation], median 5x5, blur.
cv::Mat_<float> ip_basic_fast(const cv::Mat_<float>& sparse, const IpBasicOptions& options = {});
// "multiscale": per depth bin cross dilations (7x7 near, 5x5 mid, 3x3 far; nearer bins override),
// 5x5 closing, median on valid pixels, 9x9 hole fill, [extrapolation], median 5x5, blur.
cv::Mat_<float> ip_basic_multiscale(const cv::Mat_<float>& sparse, const IpBasicOptions& options = {});

}  // namespace rgbl
