#include "rgbl/depth/ip_basic.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/depth/completion.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace rgbl {

void IpBasicOptions::validate() const {
  require(max_depth > 0.0F && std::isfinite(max_depth), "ip_basic.max_depth", "a finite depth > 0 m");
  require(near_depth > 0.0F, "ip_basic.near_depth", "a depth > 0 m");
  require(far_depth > near_depth && far_depth < max_depth, "ip_basic.far_depth",
          "a depth between ip_basic.near_depth and ip_basic.max_depth");
}

namespace {

// Inverted depth values below this are "empty" (IP-Basic's 0.1 m guard).
constexpr float kEmpty = 0.1F;

cv::Mat full(int size) { return cv::Mat::ones(size, size, CV_8U); }

cv::Mat_<float> invert(const cv::Mat_<float>& sparse, float max_depth) {
  cv::Mat_<float> v(sparse.size(), 0.0F);
  for (int y = 0; y < sparse.rows; ++y) {
    const float* d = sparse[y];
    float* out = v[y];
    for (int x = 0; x < sparse.cols; ++x) out[x] = (d[x] > kEmpty && d[x] < max_depth) ? max_depth - d[x] : 0.0F;
  }
  return v;
}

cv::Mat_<float> invert_back(const cv::Mat_<float>& v, float max_depth) {
  cv::Mat_<float> d(v.size(), 0.0F);
  for (int y = 0; y < v.rows; ++y) {
    const float* in = v[y];
    float* out = d[y];
    for (int x = 0; x < v.cols; ++x) out[x] = in[x] > kEmpty ? max_depth - in[x] : 0.0F;
  }
  return d;
}

// Empty pixels of v take the value of a dilation with `element`.
void fill_empty(cv::Mat_<float>& v, const cv::Mat& element) {
  cv::Mat dilated;
  cv::dilate(v, dilated, element);
  dilated.copyTo(v, v < kEmpty);
}

// Each column's top-most depth is copied to every pixel above it, then the remaining holes are filled
// from a 31x31 dilation.
void extrapolate(cv::Mat_<float>& v) {
  for (int x = 0; x < v.cols; ++x) {
    int top = 0;
    while (top < v.rows && v(top, x) <= kEmpty) ++top;
    if (top == v.rows) continue;
    const float value = v(top, x);
    for (int y = 0; y < top; ++y) v(y, x) = value;
  }
  fill_empty(v, full(31));
}

void blur(cv::Mat_<float>& v, IpBasicBlur type) {
  if (type == IpBasicBlur::bilateral) {
    cv::Mat_<float> out;
    cv::bilateralFilter(v, out, 5, 1.5, 2.0);
    v = out;
  } else {
    cv::Mat blurred;
    cv::GaussianBlur(v, blurred, cv::Size(5, 5), 0.0);
    blurred.copyTo(v, v > kEmpty);
  }
}

void median_on_valid(cv::Mat_<float>& v) {
  cv::Mat blurred;
  cv::medianBlur(v, blurred, 5);
  blurred.copyTo(v, v > kEmpty);
}

}  // namespace

cv::Mat_<float> ip_basic_fast(const cv::Mat_<float>& sparse, const IpBasicOptions& options) {
  options.validate();
  cv::Mat_<float> v = invert(sparse, options.max_depth);
  cv::dilate(v, v, Kernel::diamond(5).structuring_element());
  cv::morphologyEx(v, v, cv::MORPH_CLOSE, full(5));
  fill_empty(v, full(7));
  if (options.extrapolate) extrapolate(v);
  cv::medianBlur(v, v, 5);
  blur(v, options.blur);
  return invert_back(v, options.max_depth);
}

cv::Mat_<float> ip_basic_multiscale(const cv::Mat_<float>& sparse, const IpBasicOptions& options) {
  options.validate();
  const cv::Mat_<float> inverted = invert(sparse, options.max_depth);
  const float near_v = options.max_depth - options.near_depth;  // inverted: larger is nearer
  const float far_v = options.max_depth - options.far_depth;
  cv::Mat_<float> near_bin(inverted.size(), 0.0F), mid_bin(inverted.size(), 0.0F), far_bin(inverted.size(), 0.0F);
  inverted.copyTo(near_bin, inverted >= near_v);
  inverted.copyTo(mid_bin, (inverted < near_v) & (inverted >= far_v));
  inverted.copyTo(far_bin, (inverted < far_v) & (inverted > kEmpty));
  cv::dilate(near_bin, near_bin, Kernel::cross(7).structuring_element());
  cv::dilate(mid_bin, mid_bin, Kernel::cross(5).structuring_element());
  cv::dilate(far_bin, far_bin, Kernel::cross(3).structuring_element());
  cv::Mat_<float> v = far_bin;
  mid_bin.copyTo(v, mid_bin > kEmpty);
  near_bin.copyTo(v, near_bin > kEmpty);

  cv::morphologyEx(v, v, cv::MORPH_CLOSE, full(5));
  median_on_valid(v);
  fill_empty(v, full(9));
  if (options.extrapolate) extrapolate(v);
  median_on_valid(v);
  blur(v, options.blur);
  return invert_back(v, options.max_depth);
}

}  // namespace rgbl
