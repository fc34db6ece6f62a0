// `stereo_sparse`: keypoint-only stereo depth (see StereoSparseSourceOptions). Per left keypoint:
// texture test, SAD search along the row on the half-resolution level over the whole disparity range
// with a uniqueness test, then a +-3 px SAD search at full resolution and a parabola through the three
// costs around the minimum for the sub-pixel disparity.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "rgbl/core/cpu_dispatch.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/depth/sources.hpp"
#include "source_checks.hpp"


namespace rgbl {

void StereoSparseSourceOptions::validate() const {
  require(max_disparity >= 4 && max_disparity <= 1024, "stereo_sparse.max_disparity", "a disparity in [4, 1024] px");
  // 15 x 15 x 255 still fits the 16-bit cost accumulators
  require(window >= 3 && window <= 15 && window % 2 == 1, "stereo_sparse.window", "an odd size in [3, 15]");
  require(coarse_window >= 3 && coarse_window <= 15 && coarse_window % 2 == 1, "stereo_sparse.coarse_window",
          "an odd size in [3, 15]");
  require(uniqueness_ratio >= 0 && uniqueness_ratio < 100, "stereo_sparse.uniqueness_ratio",
          "a percentage in [0, 100)");
  require(min_texture >= 0.0F, "stereo_sparse.min_texture", "a gradient >= 0");
  require(max_mean_sad > 0.0F, "stereo_sparse.max_mean_sad", "a grey-level difference > 0");
  require(min_disparity_px > 0.0F, "stereo_sparse.min_disparity_px", "a disparity > 0 px");
  require(max_depth > 0.0F, "stereo_sparse.max_depth", "a depth > 0 m");
  require(disparity_sigma_px >= 0.0F, "stereo_sparse.disparity_sigma_px", "a disparity >= 0 px");
  require(dense_step >= 1, "stereo_sparse.dense_step", "a pixel step >= 1");
}

namespace {

constexpr int kLanes = 16;  // 16-bit costs in a 256-bit vector
int padded(int n) { return (n + kLanes - 1) / kLanes * kLanes; }

// cost[k] = SAD between the left window centred at (xl, y) and the right window centred at (x0 + k, y),
// for k in [0, n). The inner loop runs over contiguous right pixels, so it vectorises across
// candidates (16-bit lanes).
RGBL_CLONES_AVX2
void row_sad(const cv::Mat& left, const cv::Mat& right, int xl, int y, int half, int x0, int n, std::uint16_t* cost) {
  std::fill(cost, cost + n, std::uint16_t{0});
  for (int j = -half; j <= half; ++j) {
    const std::uint8_t* l = left.ptr<std::uint8_t>(y + j) + xl;
    const std::uint8_t* r = right.ptr<std::uint8_t>(y + j) + x0;
    for (int i = -half; i <= half; ++i) {
      const std::uint8_t lv = l[i];
      const std::uint8_t* rr = r + i;
      for (int k = 0; k < n; ++k) {
        const std::uint8_t rv = rr[k];
        cost[k] = static_cast<std::uint16_t>(cost[k] + static_cast<std::uint8_t>(rv > lv ? rv - lv : lv - rv));
      }
    }
  }
}

// Sum of squared differences between the left window at (xl, y) and the right window at (xr, y).
int ssd(const cv::Mat& left, const cv::Mat& right, int xl, int y, int half, int xr) {
  int sum = 0;
  for (int j = -half; j <= half; ++j) {
    const std::uint8_t* l = left.ptr<std::uint8_t>(y + j) + xl;
    const std::uint8_t* r = right.ptr<std::uint8_t>(y + j) + xr;
    for (int i = -half; i <= half; ++i) {
      const int diff = static_cast<int>(l[i]) - static_cast<int>(r[i]);
      sum += diff * diff;
    }
  }
  return sum;
}

// Mean |horizontal gradient| over the window: flat patches have no reliable SAD minimum.
float texture(const cv::Mat& image, int x, int y, int half) {
  int sum = 0;
  for (int j = -half; j <= half; ++j) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y + j) + x;
    for (int i = -half; i < half; ++i) sum += std::abs(static_cast<int>(row[i + 1]) - static_cast<int>(row[i]));
  }
  return static_cast<float>(sum) / static_cast<float>((2 * half + 1) * (2 * half));
}

class StereoSparseDepthSource final : public DepthSource {
 public:
  StereoSparseDepthSource(const StereoSparseSourceOptions& options, const DepthSourceContext& context)
      : camera_(context.calibration.camera), baseline_(context.stereo_baseline), options_(options) {
    options_.validate();
    detail::require_stereo_baseline(baseline_);
    fb_ = static_cast<float>(camera_.fx * baseline_);
  }

  std::string_view name() const override { return "stereo_sparse"; }

  void prepare(const SensorFrame& frame) override {
    if (frame.image.empty() || frame.image_right.empty()) {
      throw ConfigError("frame.image_right",
                        "a rectified stereo pair (image and image_right) for the stereo_sparse source");
    }
    detail::require_camera_size(frame.image, camera_, "frame.image");
    detail::require_camera_size(frame.image_right, camera_, "frame.image_right");
    left_ = detail::grey_image(frame.image);
    right_ = detail::grey_image(frame.image_right);
    if (left_.depth() != CV_8U || right_.depth() != CV_8U) {
      throw ConfigError("frame.image", "8-bit images (CV_8UC1 or CV_8UC3) for the stereo_sparse source");
    }
    cv::pyrDown(left_, left_half_);
    cv::Mat right_half;
    cv::pyrDown(right_, right_half);
    // The searched images get kLanes columns of padding so that row_sad always evaluates whole vectors
    // of candidates (the extra ones read the padding and are ignored).
    cv::copyMakeBorder(right_, right_padded_, 0, 0, 0, kLanes, cv::BORDER_CONSTANT, cv::Scalar(0));
    if (options_.left_right_check) {
      cv::copyMakeBorder(left_half_, left_half_padded_, 0, 0, 0, kLanes, cv::BORDER_CONSTANT, cv::Scalar(0));
    }
    cv::copyMakeBorder(right_half, right_half_padded_, 0, 0, 0, kLanes, cv::BORDER_CONSTANT, cv::Scalar(0));
  }

  void sample(std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out) const override {
    std::vector<std::uint16_t> cost(static_cast<std::size_t>(padded(options_.max_disparity / 2 + 2)));
    for (std::size_t i = 0; i < pixels.size(); ++i) out[i] = match(pixels[i], cost);
  }

  cv::Mat_<float> dense_depth() const override {
    cv::Mat_<float> depth(camera_.height, camera_.width, 0.0F);
    if (left_.empty()) return depth;
    std::vector<std::uint16_t> cost(static_cast<std::size_t>(padded(options_.max_disparity / 2 + 2)));
    for (int y = 0; y < depth.rows; y += options_.dense_step) {
      for (int x = 0; x < depth.cols; x += options_.dense_step) {
        depth(y, x) = match(Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y)), cost).z;
      }
    }
    return depth;
  }

 private:
  // Left-right check on the half level: the right window at xr (matched at disparity dc) searched
  // along the left row must come back to within 1 px of dc (occlusions and wrong matches do not).
  bool consistent(int xr, int y, int half, int dc, std::vector<std::uint16_t>& cost) const {
    const int n = std::min((options_.max_disparity + 1) / 2, left_half_.cols - 1 - half - xr) + 1;
    if (n < 2) return true;  // nothing to check against at the right border
    row_sad(right_half_padded_, left_half_padded_, xr, y, half, xr, padded(n), cost.data());
    int best = 0;
    for (int k = 1; k < n; ++k) best = cost[static_cast<std::size_t>(k)] < cost[static_cast<std::size_t>(best)] ? k : best;
    return std::abs(best - dc) <= 1;
  }

  KeypointDepth match(const Eigen::Vector2f& px, std::vector<std::uint16_t>& cost) const {
    const int h = options_.window / 2;
    const int x = static_cast<int>(std::lround(px.x()));
    const int y = static_cast<int>(std::lround(px.y()));
    if (y - h < 0 || y + h >= left_.rows || x - h < 0 || x + h >= left_.cols) return {};
    if (texture(left_, x, y, h) < options_.min_texture) return {};

    // Coarse: the whole range on the half-resolution level; right candidate xr = x1 - d.
    const int hc = options_.coarse_window / 2;
    const int x1 = x / 2;
    const int y1 = y / 2;
    if (y1 - hc < 0 || y1 + hc >= left_half_.rows || x1 - hc < 0 || x1 + hc >= left_half_.cols) return {};
    // (row_sad reads up to padded(n) - 1 candidates right of x0: within the kLanes padding columns)
    const int dc_max = std::min((options_.max_disparity + 1) / 2, x1 - hc);
    if (dc_max < 2) return {};
    const int nc = dc_max + 1;
    row_sad(left_half_, right_half_padded_, x1, y1, hc, x1 - dc_max, padded(nc), cost.data());
    int best = 0;
    for (int k = 1; k < nc; ++k)
      best = cost[static_cast<std::size_t>(k)] < cost[static_cast<std::size_t>(best)] ? k : best;
    const int best_cost = cost[static_cast<std::size_t>(best)];
    for (int k = 0; k < nc; ++k) {
      if (std::abs(k - best) > 1 &&
          cost[static_cast<std::size_t>(k)] * (100 - options_.uniqueness_ratio) <= best_cost * 100) {
        return {};  // repetitive texture or occlusion: another disparity is nearly as good
      }
    }
    const int dc = dc_max - best;
    if (options_.left_right_check && !consistent(x1 - dc, y1, hc, dc, cost)) return {};

    // Fine: +-3 px around 2 * dc at full resolution (the half level rounds x and the disparity).
    const int d_lo = std::max(2 * dc - 3, 0);
    const int d_hi = std::min({2 * dc + 3, options_.max_disparity, x - h});
    const int nf = d_hi - d_lo + 1;
    if (nf < 3) return {};
    const int x0 = x - d_hi;
    row_sad(left_, right_padded_, x, y, h, x0, padded(nf), cost.data());
    int kf = 0;
    for (int k = 1; k < nf; ++k) kf = cost[static_cast<std::size_t>(k)] < cost[static_cast<std::size_t>(kf)] ? k : kf;
    if (kf == 0 || kf == nf - 1) return {};  // minimum on the border: no parabola, likely a wrong coarse match
    const float c0 = cost[static_cast<std::size_t>(kf)];
    const float area = static_cast<float>(options_.window * options_.window);
    if (c0 > options_.max_mean_sad * area) return {};
    // Sub-pixel: a parabola through the SSD (not the SAD) at the three positions around the minimum.
    // SSD is locally quadratic in the shift, so the vertex is unbiased; a parabola on SAD (V-shaped
    // near the minimum) pulls towards the integer and was off by 0.15 px at quarter-pixel shifts.
    const float cm = static_cast<float>(ssd(left_, right_, x, y, h, x0 + kf - 1));
    const float cs = static_cast<float>(ssd(left_, right_, x, y, h, x0 + kf));
    const float cp = static_cast<float>(ssd(left_, right_, x, y, h, x0 + kf + 1));
    const float curvature = cm + cp - 2.0F * cs;
    if (curvature <= 0.0F) return {};
    const float xr = static_cast<float>(x0 + kf) + (cm - cp) / (2.0F * curvature);
    const float d = static_cast<float>(x) - xr;
    if (d < options_.min_disparity_px) return {};
    const float z = fb_ / d;
    if (z > options_.max_depth) return {};
    KeypointDepth out;
    out.z = z;
    out.sample_distance_px = 0.0F;  // measured at the keypoint itself
    const float s = options_.disparity_sigma_px;
    out.spread = d > s ? fb_ / (d - s) - fb_ / (d + s) : z;
    return out;
  }

  PinholeCamera camera_;
  double baseline_;
  StereoSparseSourceOptions options_;
  float fb_ = 0.0F;
  cv::Mat left_, right_, left_half_, right_padded_, right_half_padded_, left_half_padded_;
};

}  // namespace

std::unique_ptr<DepthSource> make_stereo_sparse_source(const StereoSparseSourceOptions& options,
                                                       const DepthSourceContext& context) {
  return std::make_unique<StereoSparseDepthSource>(options, context);
}

}  // namespace rgbl
