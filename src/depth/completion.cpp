#include "rgbl/depth/completion.hpp"

#include "rgbl/core/error.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace rgbl {

Kernel::Kernel(KernelShape shape, int size) : shape_(shape), radius_(size / 2) {
  require(size >= 1 && size % 2 == 1 && size <= 63, "kernel.size", "an odd side length in [1, 63]");
}

int Kernel::half_width(int dy) const {
  const int a = std::abs(dy);
  if (a > radius_) return -1;
  switch (shape_) {
    case KernelShape::diamond: return radius_ - a;
    case KernelShape::rectangle: return radius_;
    case KernelShape::cross: return a == 0 ? radius_ : 0;
  }
  return -1;
}

int Kernel::cell_count() const {
  int n = 0;
  for (int dy = -radius_; dy <= radius_; ++dy) n += 2 * half_width(dy) + 1;
  return n;
}

cv::Mat Kernel::structuring_element() const {
  cv::Mat element(size(), size(), CV_8U, cv::Scalar(0));
  for (int dy = -radius_; dy <= radius_; ++dy) {
    const int h = half_width(dy);
    for (int dx = -h; dx <= h; ++dx) element.at<std::uint8_t>(dy + radius_, dx + radius_) = 1;
  }
  return element;
}

std::string Kernel::name() const {
  const char* shape = shape_ == KernelShape::diamond ? "diamond" : shape_ == KernelShape::rectangle ? "rectangle" : "cross";
  return std::string(shape) + std::to_string(size());
}

KernelShape parse_kernel_shape(std::string_view text, const char* key) {
  if (text == "diamond") return KernelShape::diamond;
  if (text == "rectangle") return KernelShape::rectangle;
  if (text == "cross") return KernelShape::cross;
  throw ConfigError(key, "one of: diamond, rectangle, cross");
}

void DilationOptions::validate() const {
  require(size >= 1 && size % 2 == 1 && size <= 63, "dilation.size", "an odd side length in [1, 63]");
  require(max_depth > 0.0F && std::isfinite(max_depth), "dilation.max_depth", "a finite depth > 0 m");
}

namespace {

// The two float operations of the reference, shared by the dense and the keypoint paths so that both
// round exactly like it: v = M - d, then anything that maps to M (empty, or too small to matter) -> 0.
// Negative v (d > M) is clamped to 0: it can never win against an empty neighbour and maps back to 0.
struct Inversion {
  float m;
  float threshold;  // largest float below M: "> threshold" means "== M" (or beyond)

  explicit Inversion(float max_depth) : m(max_depth), threshold(std::nextafter(max_depth, 0.0F)) {}

  float forward(float d) const {
    const float v = m - d;
    const float kept = v > threshold ? 0.0F : v;
    return kept > 0.0F ? kept : 0.0F;
  }
  float back(float v) const {
    const float d = m - v;
    return d > threshold ? 0.0F : d;
  }
};

// Row-wise running max of width 2h+1 from the level h-1 (width 2h-1) of the same row: the union of
// the windows at x-1 and x+1. Rows carry `pad` zero cells on both sides.
void widen(const float* __restrict narrow, float* __restrict wide, int width) {
  for (int x = 0; x < width; ++x) {
    const float a = narrow[x - 1], b = narrow[x + 1];
    wide[x] = a > b ? a : b;
  }
}

}  // namespace

void dilate_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, cv::Mat_<float>& dense) {
  options.validate();
  CV_Assert(sparse.data != dense.data || sparse.empty());
  const Kernel kernel = options.kernel();
  const int width = sparse.cols;
  const int height = sparse.rows;
  dense.create(height, width);
  if (width == 0 || height == 0) return;
  const int radius = kernel.radius();
  const Inversion inv(options.max_depth);

  // A ring of 2R+1 input rows; for each, the running maxima of every half-width 0..R, each padded
  // with R+1 zero cells on both sides so that widening never reads outside.
  const int pad = radius + 1;
  const int stride = width + 2 * pad;
  const int ring = 2 * radius + 1;
  const int levels = radius + 1;
  std::vector<float> buffer(static_cast<std::size_t>(ring) * levels * stride, 0.0F);
  std::vector<std::uint8_t> row_valid(static_cast<std::size_t>(height), 0);
  auto level_row = [&](int row, int level) {
    return buffer.data() + (static_cast<std::size_t>(row % ring) * levels + level) * stride + pad;
  };

  // Fills ring slot of input row r; returns whether the row holds any depth.
  auto load_row = [&](int r) {
    const float* src = sparse[r];
    float* v0 = level_row(r, 0);
    float any = 0.0F;
    for (int x = 0; x < width; ++x) {
      const float v = inv.forward(src[x]);
      v0[x] = v;
      any = any > v ? any : v;
    }
    const bool valid = any > 0.0F;
    row_valid[static_cast<std::size_t>(r)] = valid ? 1 : 0;
    if (valid) {
      for (int level = 1; level < levels; ++level) {
        if (level == 1) {
          float* v1 = level_row(r, 1);
          for (int x = 0; x < width; ++x) {
            const float a = v0[x - 1], b = v0[x], c = v0[x + 1];
            const float ab = a > b ? a : b;
            v1[x] = ab > c ? ab : c;
          }
        } else {
          widen(level_row(r, level - 1), level_row(r, level), width);
        }
      }
    }
  };

  const int rows_ahead = std::min(radius, height);
  for (int r = 0; r < rows_ahead; ++r) load_row(r);

  std::vector<const float*> sources;
  sources.reserve(static_cast<std::size_t>(ring));
  for (int y = 0; y < height; ++y) {
    if (y + radius < height) load_row(y + radius);
    sources.clear();
    for (int dy = -radius; dy <= radius; ++dy) {
      const int r = y + dy;
      if (r < 0 || r >= height || row_valid[static_cast<std::size_t>(r)] == 0) continue;
      const int h = kernel.half_width(dy);
      sources.push_back(level_row(r, h));
    }
    float* out = dense[y];
    if (sources.empty()) {
      std::memset(out, 0, sizeof(float) * static_cast<std::size_t>(width));
      continue;
    }
    const float* first = sources[0];
    for (int x = 0; x < width; ++x) out[x] = first[x];
    for (std::size_t s = 1; s < sources.size(); ++s) {
      const float* src = sources[s];
      for (int x = 0; x < width; ++x) out[x] = out[x] > src[x] ? out[x] : src[x];
    }
    for (int x = 0; x < width; ++x) out[x] = inv.back(out[x]);
  }
}

cv::Mat_<float> dilate_depth(const cv::Mat_<float>& sparse, const DilationOptions& options) {
  cv::Mat_<float> dense;
  dilate_depth(sparse, options, dense);
  return dense;
}

KeypointDepth lookup_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, const Eigen::Vector2f& pixel) {
  KeypointDepth result;
  const float fx = std::floor(pixel.x() + 0.5F), fy = std::floor(pixel.y() + 0.5F);
  if (!(fx >= 0.0F && fy >= 0.0F && fx < static_cast<float>(sparse.cols) && fy < static_cast<float>(sparse.rows))) {
    return result;
  }
  const int x = static_cast<int>(fx), y = static_cast<int>(fy);
  const Kernel kernel = options.kernel();
  const Inversion inv(options.max_depth);
  const int radius = kernel.radius();
  float best = 0.0F;
  float best_distance2 = std::numeric_limits<float>::max();
  float lo = std::numeric_limits<float>::max(), hi = 0.0F;
  for (int dy = -radius; dy <= radius; ++dy) {
    const int r = y + dy;
    if (r < 0 || r >= sparse.rows) continue;
    const int h = kernel.half_width(dy);
    const float* row = sparse[r];
    const int x0 = std::max(0, x - h), x1 = std::min(sparse.cols - 1, x + h);
    for (int c = x0; c <= x1; ++c) {
      const float d = row[c];
      const float v = inv.forward(d);
      if (v <= 0.0F) continue;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
      const float ex = static_cast<float>(c) - pixel.x(), ey = static_cast<float>(r) - pixel.y();
      const float distance2 = ex * ex + ey * ey;
      if (v > best || (v == best && distance2 < best_distance2)) {
        best = v;
        best_distance2 = distance2;
      }
    }
  }
  if (best <= 0.0F) return result;
  result.z = inv.back(best);
  if (result.z <= 0.0F) return result;
  result.sample_distance_px = std::sqrt(best_distance2);
  result.spread = hi - lo;
  return result;
}

void lookup_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, std::span<const Eigen::Vector2f> pixels,
                  std::span<KeypointDepth> out) {
  options.validate();
  CV_Assert(out.size() == pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) out[i] = lookup_depth(sparse, options, pixels[i]);
}

double depth_density(const cv::Mat_<float>& depth) {
  if (depth.empty()) return 0.0;
  std::size_t count = 0;
  for (int y = 0; y < depth.rows; ++y) {
    const float* row = depth[y];
    for (int x = 0; x < depth.cols; ++x) count += row[x] > 0.0F ? 1U : 0U;
  }
  return static_cast<double>(count) / static_cast<double>(depth.total());
}

}  // namespace rgbl
