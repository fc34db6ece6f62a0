#include "rgbl/depth/completion.hpp"

#include "rgbl/core/cpu_dispatch.hpp"
#include "rgbl/core/error.hpp"

#include <Eigen/Cholesky>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <optional>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>

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
// (The keypoint lookup uses these directly; the dense kernel the equivalent key form below.)
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

// The dense kernel works on depth directly, "empty as +infinity", as a min filter over the bit
// patterns of the depths (for non-negative floats, integer order is float order), so it runs on the
// integer vector units. A depth is a key when the reference would keep it (0 < M - d <= below-M, i.e.
// its bits lie in [lowest_key, bits(M))); every other value becomes +inf. The winner d* maps back
// through the reference's own float operations, below_M-threshold(M - (M - d*)), which also sends
// +inf to 0. Equal to the reference because M - d is monotone: the largest inverted value is the
// inverted smallest depth.
using Keys = std::int32_t __attribute__((vector_size(32)));
using Floats = float __attribute__((vector_size(32)));
using KeysU = std::uint32_t __attribute__((vector_size(32)));
constexpr int kLanes = 8;
constexpr std::int32_t kEmpty = 0x7F800000;  // +inf

// Internal helpers, always inlined: their vector ABI never matters (-Wno-psabi for this file).
[[gnu::always_inline]] inline Keys load(const std::int32_t* p) {
  Keys v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
[[gnu::always_inline]] inline Keys load(const float* p) {
  Keys v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
[[gnu::always_inline]] inline void store(std::int32_t* p, Keys v) { std::memcpy(p, &v, sizeof(v)); }
[[gnu::always_inline]] inline void store(float* p, Floats v) { std::memcpy(p, &v, sizeof(v)); }
[[gnu::always_inline]] inline Keys vmin(Keys a, Keys b) { return a < b ? a : b; }

// Smallest bit pattern of a depth the reference keeps: M - d must round below M.
std::int32_t lowest_key(const Inversion& inv) {
  std::int32_t lo = 1, hi = std::bit_cast<std::int32_t>(inv.m);  // forward(lo) == 0 < forward(hi - 1)
  if (inv.forward(std::bit_cast<float>(lo)) > 0.0F) return lo;
  while (hi - lo > 1) {
    const std::int32_t mid = lo + (hi - lo) / 2;
    if (inv.forward(std::bit_cast<float>(mid)) > 0.0F) hi = mid;
    else lo = mid;
  }
  return hi;
}

// Scratch rows for one dilation: a ring of 2R+1 input rows, each with its running minima of every
// half-width 0..R ("levels"), padded with +inf keys so that widening and the vector tails never read
// outside. Level h of a row holds min(key[x-h .. x+h]).
class RowRing {
 public:
  RowRing(int width, int slots, int levels)
      : width_(width), ring_(slots), levels_(levels),
        stride_(round_up(round_up(width, kLanes) + 2 * kPad, kLineInts)),
        buffer_(static_cast<std::size_t>(ring_) * static_cast<std::size_t>(levels_) * static_cast<std::size_t>(stride_) +
                    kLineInts,
                kEmpty) {
    // Rows start on a cache line, so that the aligned half of the loads never straddles two lines.
    const auto misalignment = static_cast<int>(reinterpret_cast<std::uintptr_t>(buffer_.data()) % 64);
    base_ = buffer_.data() + (round_up(misalignment, 64) - misalignment) / 4;
  }
  RowRing(const RowRing&) = delete;
  RowRing& operator=(const RowRing&) = delete;

  std::int32_t* row(int r, int level) {
    return base_ +
           (static_cast<std::size_t>(r % ring_) * static_cast<std::size_t>(levels_) + static_cast<std::size_t>(level)) *
               static_cast<std::size_t>(stride_) +
           kPad;
  }
  int vector_width() const { return round_up(width_, kLanes); }

 private:
  static constexpr int kPad = 16;       // +inf keys before and after each row (>= 1 + a vector's overrun)
  static constexpr int kLineInts = 16;  // 64-byte cache line
  static constexpr int round_up(int n, int m) { return (n + m - 1) / m * m; }

  int width_, ring_, levels_, stride_;
  std::vector<std::int32_t> buffer_;
  std::int32_t* base_ = nullptr;
};

// Keys of one input row into level 0; returns whether any bit is set. The padding stays +inf.
RGBL_CLONES_AVX2 bool key_row(const float* __restrict src, std::int32_t* __restrict dst, int width, std::int32_t lo,
                              std::int32_t hi) {
  // lo <= bits < hi as one unsigned comparison, (bits - lo) < (hi - lo), done signed with the sign bit
  // flipped. Negative depths have "negative" bits: dropped.
  using Unsigned = std::uint32_t __attribute__((vector_size(32)));
  constexpr std::uint32_t kSign = 0x80000000U;
  const Unsigned vlo = Unsigned{} + static_cast<std::uint32_t>(lo);
  const Keys limit = Keys{} + std::bit_cast<std::int32_t>((static_cast<std::uint32_t>(hi) - static_cast<std::uint32_t>(lo)) ^ kSign);
  const Keys empty = Keys{} + kEmpty;
  Keys any{};
  int x = 0;
  for (; x + kLanes <= width; x += kLanes) {
    const Keys bits = load(src + x);
    any |= bits;
    const Keys offset = std::bit_cast<Keys>((std::bit_cast<Unsigned>(bits) - vlo) ^ kSign);
    store(dst + x, offset < limit ? bits : empty);
  }
  bool tail_any = false;
  for (; x < width; ++x) {
    const auto bits = std::bit_cast<std::int32_t>(src[x]);
    const bool keep = bits >= lo && bits < hi;
    dst[x] = keep ? bits : kEmpty;
    tail_any |= bits != 0;
  }
  for (int i = 0; i < kLanes; ++i) tail_any |= any[i] != 0;
  return tail_any;
}

// Whether a row holds any non-zero bit, stopping at the first.
RGBL_CLONES_AVX2 bool has_depth(const float* row, int width) {
  int x = 0;
  for (; x + 4 * kLanes <= width; x += 4 * kLanes) {
    const Keys any = load(row + x) | load(row + x + kLanes) | load(row + x + 2 * kLanes) | load(row + x + 3 * kLanes);
    const Keys zero{};
    if (std::memcmp(&any, &zero, sizeof(any)) != 0) return true;
  }
  for (; x < width; ++x) {
    if (std::bit_cast<std::uint32_t>(row[x]) != 0) return true;
  }
  return false;
}

// Level h from level h-1: the union of the windows at x-1 and x+1 (level 1 reads level 0 at x too).
RGBL_CLONES_AVX2 void widen_row(const std::int32_t* __restrict narrow, std::int32_t* __restrict wide, int vector_width,
                                bool first) {
  if (first) {
    for (int x = 0; x < vector_width; x += kLanes)
      store(wide + x, vmin(vmin(load(narrow + x - 1), load(narrow + x)), load(narrow + x + 1)));
  } else {
    for (int x = 0; x < vector_width; x += kLanes) store(wide + x, vmin(load(narrow + x - 1), load(narrow + x + 1)));
  }
}

// One output row: the min over N level rows, mapped back like the reference. N is a compile-time
// constant so that the row pointers live in registers and the min chain is unrolled.
template <int N>
[[gnu::always_inline]] inline void combine_fixed(const std::int32_t* const* sources, float* __restrict out, int width,
                                                 float m, float threshold) {
  const std::int32_t* rows[N];
  for (int s = 0; s < N; ++s) rows[s] = sources[s];
  const Floats vm = Floats{} + m, vt = Floats{} + threshold, zero{};
  int x = 0;
  for (; x + kLanes <= width; x += kLanes) {
    Keys acc = load(rows[0] + x);
    for (int s = 1; s < N; ++s) acc = vmin(acc, load(rows[s] + x));
    const Floats d = vm - (vm - std::bit_cast<Floats>(acc));  // +inf -> M - (-inf) = +inf -> 0 below
    store(out + x, d > vt ? zero : d);
  }
  for (; x < width; ++x) {
    std::int32_t acc = rows[0][x];
    for (int s = 1; s < N; ++s) acc = std::min(acc, rows[s][x]);
    const float d = m - (m - std::bit_cast<float>(acc));
    out[x] = d > threshold ? 0.0F : d;
  }
}

RGBL_CLONES_AVX2 void combine_rows(const std::int32_t* const* sources, int count, float* __restrict out, int width,
                                   float m, float threshold) {
  switch (count) {
    case 1:
      return combine_fixed<1>(sources, out, width, m, threshold);
    case 2:
      return combine_fixed<2>(sources, out, width, m, threshold);
    case 3:
      return combine_fixed<3>(sources, out, width, m, threshold);
    case 4: return combine_fixed<4>(sources, out, width, m, threshold);
    case 5: return combine_fixed<5>(sources, out, width, m, threshold);
    case 6: return combine_fixed<6>(sources, out, width, m, threshold);
    case 7: return combine_fixed<7>(sources, out, width, m, threshold);
    case 8: return combine_fixed<8>(sources, out, width, m, threshold);
    case 9: return combine_fixed<9>(sources, out, width, m, threshold);
    default: break;
  }
  // kernels taller than 9 rows: a plain loop (rare, not benchmarked)
  for (int x = 0; x < width; ++x) {
    std::int32_t acc = sources[0][x];
    for (int s = 1; s < count; ++s) acc = std::min(acc, sources[s][x]);
    const float d = m - (m - std::bit_cast<float>(acc));
    out[x] = d > threshold ? 0.0F : d;
  }
}

// The default 5x5 diamond, fused: it reads the float depth rows directly, with no conversion pass and
// no key rows. The key of a depth is its bit pattern minus lowest_key, as an unsigned number: the
// depths the reference keeps map to [0, span) in depth order, and everything else (0, tiny, >= M,
// negative, NaN) wraps or lands at >= span, so an unsigned min picks the nearest kept depth whenever
// there is one. Keys are held with the sign bit flipped, so signed vector compares give unsigned
// order (GCC 12 scalarises unsigned compare-and-select on 512-bit vectors). G output rows per pass
// share the row runs (widths 1, 3, 5) built in registers. S is the key vector: 8 lanes (AVX2 or
// baseline) or 16 (AVX-512, whose 32 registers hold a pass's 30 runs). Fusing removed a conversion
// pass that took a third of the time.
constexpr int kDiamondGroup = 8;  // output rows per pass (measured before fusing: 4 was 7% slower, 16 spilled)
constexpr int kMaxLanes = 16;

using Keys16 = std::int32_t __attribute__((vector_size(64)));
using Keys16U = std::uint32_t __attribute__((vector_size(64)));
using Floats16 = float __attribute__((vector_size(64)));

struct DiamondBlock {
  const float* in;          // input row y - 2 (G + 4 rows are read)
  std::ptrdiff_t in_step;   // floats between input rows
  float* out;               // output row y (G rows are written)
  std::ptrdiff_t out_step;  // floats between output rows
  int x0, x1;               // output columns; input columns [x0 - 2, x1 + 2 + lanes) must be readable
  std::uint32_t lo, span;   // key = bits - lo; kept depths have key < span
  float m, threshold;
};

// a + b with wrap-around (two's complement), for vectors of int32.
template <class S>
[[gnu::always_inline]] inline S wrap_add(S a, std::uint32_t b) {
  using U = std::conditional_t<sizeof(S) == sizeof(Keys), KeysU, Keys16U>;
  return std::bit_cast<S>(std::bit_cast<U>(a) + b);
}
template <class S>
[[gnu::always_inline]] inline S load_keys(const float* p, std::uint32_t offset) {
  S v;
  std::memcpy(&v, p, sizeof(v));
  return wrap_add(v, offset);
}
template <class S>
[[gnu::always_inline]] inline S smin(S a, S b) {
  return a < b ? a : b;
}

template <class S>
[[gnu::always_inline]] inline void diamond5_block(const DiamondBlock& b) {
  constexpr int G = kDiamondGroup;
  using F = std::conditional_t<sizeof(S) == sizeof(Floats), Floats, Floats16>;
  constexpr int lanes = static_cast<int>(sizeof(S) / sizeof(std::int32_t));
  constexpr std::uint32_t kSign = 0x80000000U;
  const std::uint32_t offset = kSign - b.lo;  // bits + offset = (bits - lo) ^ sign
  const S vspan = S{} + std::bit_cast<std::int32_t>(b.span ^ kSign);
  const S vt = S{} + std::bit_cast<std::int32_t>(b.threshold);
  const F vm = F{} + b.m;
  for (int x = b.x0; x < b.x1; x += lanes) {
    S l0[G + 4], l1[G + 4], l2[G + 4];
    for (int i = 0; i < G + 4; ++i) {
      const float* row = b.in + i * b.in_step + x;
      l0[i] = load_keys<S>(row, offset);
      if (i >= 1 && i <= G + 2) l1[i] = smin(l0[i], smin(load_keys<S>(row - 1, offset), load_keys<S>(row + 1, offset)));
      if (i >= 2 && i <= G + 1) l2[i] = smin(l1[i], smin(load_keys<S>(row - 2, offset), load_keys<S>(row + 2, offset)));
    }
    const int n = std::min(lanes, b.x1 - x);
    for (int j = 0; j < G; ++j) {
      // Capping the key at span turns "nothing kept" into M itself, which the threshold then zeroes.
      const S key = smin(smin(smin(smin(l0[j], l1[j + 1]), smin(l2[j + 2], l1[j + 3])), l0[j + 4]), vspan);
      const F back = vm - (vm - std::bit_cast<F>(wrap_add(key, 0U - offset)));  // the reference's rounding
      // Zero unless it rounds below M (an integer compare: the result is >= 0, so bit order is value order).
      const S bits = std::bit_cast<S>(back);
      const S result = bits <= vt ? bits : S{};
      float* dst = b.out + j * b.out_step + x;
      if (n == lanes) {
        std::memcpy(dst, &result, sizeof(result));
      } else {
        std::memcpy(dst, &result, sizeof(float) * static_cast<std::size_t>(n));
      }
    }
  }
}

RGBL_CLONES_AVX2 void diamond5_avx2(const DiamondBlock& b) { diamond5_block<Keys>(b); }

#if defined(RGBL_X86_DISPATCH) && !defined(RGBL_NO_AVX512)
__attribute__((target("arch=x86-64-v4"))) void diamond5_avx512(const DiamondBlock& b) { diamond5_block<Keys16>(b); }
#endif

// The widest build the CPU runs (a cached CPUID bit, nothing next to a block).
void diamond5(const DiamondBlock& b) {
#if defined(RGBL_X86_DISPATCH) && !defined(RGBL_NO_AVX512)
  if (__builtin_cpu_supports("x86-64-v4")) return diamond5_avx512(b);
#endif
  diamond5_avx2(b);
}

void dilate_diamond5(const cv::Mat_<float>& sparse, const Inversion& inv, std::int32_t lo, std::int32_t hi,
                     cv::Mat_<float>& dense) {
  constexpr int G = kDiamondGroup;
  const int width = sparse.cols, height = sparse.rows;
  DiamondBlock block{};
  block.lo = static_cast<std::uint32_t>(lo);
  block.span = static_cast<std::uint32_t>(hi) - static_cast<std::uint32_t>(lo);
  block.m = inv.m;
  block.threshold = inv.threshold;

  // Columns the passes read in place: every load of [x - 2, x + lanes + 2) stays inside the row.
  const int xa = kMaxLanes;
  const int xb = width - 2 > xa ? xa + (width - 2 - xa) / kMaxLanes * kMaxLanes : xa;
  // Everything else (the image's first and last rows, the columns left of xa and right of xb) goes
  // through a zero-padded copy of the G + 4 rows, computed into a scratch output and copied out.
  const int scratch_cols = width + 4 + 2 * kMaxLanes;
  // (not zeroed here: padded() clears what each pass reads)
  const auto scratch_in = std::make_unique_for_overwrite<float[]>(static_cast<std::size_t>((G + 4) * scratch_cols));
  const auto scratch_out = std::make_unique_for_overwrite<float[]>(static_cast<std::size_t>(G * scratch_cols));
  auto padded = [&](int y, int c0, int c1) {  // output columns [c0, c1) of rows y .. y + G - 1
    const int cols = c1 - c0;
    const int used = cols + 4 + kMaxLanes;  // what the pass reads of each scratch row
    for (int i = 0; i < G + 4; ++i) {
      float* dst = scratch_in.get() + static_cast<std::ptrdiff_t>(i) * scratch_cols;
      std::fill(dst, dst + used, 0.0F);
      const int r = y - 2 + i;
      if (r < 0 || r >= height) continue;
      const int s0 = std::max(c0 - 2, 0), s1 = std::min(c1 + 2, width);
      std::memcpy(dst + 2 + (s0 - c0), sparse[r] + s0, sizeof(float) * static_cast<std::size_t>(s1 - s0));
    }
    DiamondBlock b = block;
    b.in = scratch_in.get() + 2;
    b.in_step = scratch_cols;
    b.out = scratch_out.get();
    b.out_step = scratch_cols;
    b.x0 = 0;
    b.x1 = cols;
    diamond5(b);
    for (int j = 0; j < G && y + j < height; ++j) {
      std::memcpy(dense[y + j] + c0, scratch_out.get() + static_cast<std::ptrdiff_t>(j) * scratch_cols,
                  sizeof(float) * static_cast<std::size_t>(cols));
    }
  };

  // Rows without any sample (the top third of a KITTI frame) are only scanned: a group whose input
  // rows are all empty is zeroed. (A row with samples stops the scan at its first one.)
  std::vector<std::uint8_t> row_any(static_cast<std::size_t>(height));
  for (int r = 0; r < height; ++r) row_any[static_cast<std::size_t>(r)] = has_depth(sparse[r], width) ? 1 : 0;

  for (int y = 0; y < height; y += G) {
    bool any = false;
    for (int r = std::max(y - 2, 0); r < std::min(y + G + 2, height); ++r) any |= row_any[static_cast<std::size_t>(r)] != 0;
    if (!any) {
      for (int j = 0; j < G && y + j < height; ++j)
        std::memset(dense[y + j], 0, sizeof(float) * static_cast<std::size_t>(width));
      continue;
    }
    if (y < 2 || y + G + 2 > height || xb <= xa) {
      padded(y, 0, width);
      continue;
    }
    DiamondBlock b = block;
    b.in = sparse[y - 2];
    b.in_step = static_cast<std::ptrdiff_t>(sparse.step1());
    b.out = dense[y];
    b.out_step = static_cast<std::ptrdiff_t>(dense.step1());
    b.x0 = xa;
    b.x1 = xb;
    diamond5(b);
    padded(y, 0, xa);
    padded(y, xb, width);
  }
}

}  // namespace

std::optional<double> ring_spacing_px(const cv::Mat_<float>& sparse, std::size_t min_gaps) {
  // A band of 3 columns every 48 (one 64-byte cache line in four is read): sequence 04's 1226 px give
  // 26 bands, 966-1024 gaps a frame of the HDL-64 and 224-240 of every fourth ring (every 10th frame,
  // a throwaway script). Narrower images keep those 26 bands with a shorter stride: at 48 the
  // simulator's 613 px gave 13, too few gaps for a 16-ring scan after the occlusion filter.
  constexpr int kBand = 3, kBands = 26, kMaxStride = 48;
  const int stride = std::clamp((sparse.cols - kBand) / (kBands - 1), kBand, kMaxStride);
  const int bands = sparse.cols >= kBand ? (sparse.cols - kBand) / stride + 1 : 0;
  std::vector<int> last(static_cast<std::size_t>(bands), -1);  // per band, the last row with a sample
  std::vector<int> gaps;
  gaps.reserve(static_cast<std::size_t>(bands) * 64);
  for (int r = 0; r < sparse.rows; ++r) {
    const float* row = sparse[r];
    for (int b = 0; b < bands; ++b) {
      const float* cell = row + b * stride;
      if (!(cell[0] > 0.0F || cell[1] > 0.0F || cell[2] > 0.0F)) continue;
      int& previous = last[static_cast<std::size_t>(b)];
      if (previous >= 0 && r - previous > 1) gaps.push_back(r - previous);
      previous = r;
    }
  }
  if (gaps.size() < std::max<std::size_t>(min_gaps, 1)) return std::nullopt;
  const auto middle = gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2);
  std::nth_element(gaps.begin(), middle, gaps.end());
  return static_cast<double>(*middle);
}

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
  const std::int32_t lo = lowest_key(inv), hi = std::bit_cast<std::int32_t>(inv.m);
  if (kernel.shape() == KernelShape::diamond && radius == 2) {
    dilate_diamond5(sparse, inv, lo, hi, dense);
    return;
  }
  RowRing ring(width, 2 * radius + 1, radius + 1);
  std::vector<std::uint8_t> row_valid(static_cast<std::size_t>(height), 0);

  auto load_row = [&](int r) {
    // Rows without any sample (the top third of a KITTI frame) are only scanned, never converted.
    const bool valid = has_depth(sparse[r], width) && key_row(sparse[r], ring.row(r, 0), width, lo, hi);
    row_valid[static_cast<std::size_t>(r)] = valid ? 1 : 0;
    if (!valid) return;
    for (int level = 1; level <= radius; ++level) {
      widen_row(ring.row(r, level - 1), ring.row(r, level), ring.vector_width(), level == 1);
    }
  };

  for (int r = 0; r < std::min(radius, height); ++r) load_row(r);
  std::vector<const std::int32_t*> sources;
  sources.reserve(static_cast<std::size_t>(2 * radius + 1));
  for (int y = 0; y < height; ++y) {
    if (y + radius < height) load_row(y + radius);
    sources.clear();
    for (int dy = -radius; dy <= radius; ++dy) {
      const int r = y + dy;
      if (r < 0 || r >= height || row_valid[static_cast<std::size_t>(r)] == 0) continue;
      sources.push_back(ring.row(r, kernel.half_width(dy)));
    }
    if (sources.empty()) {
      std::memset(dense[y], 0, sizeof(float) * static_cast<std::size_t>(width));
    } else {
      combine_rows(sources.data(), static_cast<int>(sources.size()), dense[y], width, inv.m, inv.threshold);
    }
  }
}

cv::Mat_<float> dilate_depth(const cv::Mat_<float>& sparse, const DilationOptions& options) {
  cv::Mat_<float> dense;
  dilate_depth(sparse, options, dense);
  return dense;
}

namespace {

// The kernel as a list of cells, prepared once per batch of keypoints.
struct Cell {
  int dx, dy;
};

std::vector<Cell> kernel_cells(const Kernel& kernel) {
  std::vector<Cell> cells;
  cells.reserve(static_cast<std::size_t>(kernel.cell_count()));
  for (int dy = -kernel.radius(); dy <= kernel.radius(); ++dy) {
    const int h = kernel.half_width(dy);
    for (int dx = -h; dx <= h; ++dx) cells.push_back({dx, dy});
  }
  return cells;
}

// The kernel around the pixel centre nearest to a keypoint: which cells lie in the image, and their
// values. Empty (no cells) when that centre is outside the image.
class KernelWindow {
 public:
  KernelWindow(const cv::Mat_<float>& sparse, int radius, const Eigen::Vector2f& pixel) {
    const float fx = std::floor(pixel.x() + 0.5F), fy = std::floor(pixel.y() + 0.5F);
    if (!(fx >= 0.0F && fy >= 0.0F && fx < static_cast<float>(sparse.cols) && fy < static_cast<float>(sparse.rows))) {
      return;
    }
    x_ = static_cast<int>(fx);
    y_ = static_cast<int>(fy);
    cols_ = sparse.cols;
    rows_ = sparse.rows;
    inside_ = x_ >= radius && y_ >= radius && x_ + radius < cols_ && y_ + radius < rows_;
    centre_ = sparse[y_] + x_;
    step_ = static_cast<std::ptrdiff_t>(sparse.step1());
  }

  bool empty() const { return centre_ == nullptr; }
  bool holds(const Cell& c) const {
    return inside_ || (x_ + c.dx >= 0 && y_ + c.dy >= 0 && x_ + c.dx < cols_ && y_ + c.dy < rows_);
  }
  float at(const Cell& c) const { return centre_[c.dy * step_ + c.dx]; }
  // squared distance from the keypoint to the centre of cell c
  float distance2(const Cell& c, const Eigen::Vector2f& pixel) const {
    const float ex = static_cast<float>(x_ + c.dx) - pixel.x(), ey = static_cast<float>(y_ + c.dy) - pixel.y();
    return ex * ex + ey * ey;
  }

 private:
  const float* centre_ = nullptr;
  std::ptrdiff_t step_ = 0;
  int x_ = 0, y_ = 0, cols_ = 0, rows_ = 0;
  bool inside_ = false;
};

KeypointDepth lookup_one(const cv::Mat_<float>& sparse, std::span<const Cell> cells, int radius, const Inversion& inv,
                         const Eigen::Vector2f& pixel) {
  KeypointDepth result;
  const KernelWindow window(sparse, radius, pixel);
  if (window.empty()) return result;
  // First pass: the winning inverted value and the depth range; cells outside the image are skipped.
  float best = 0.0F;
  float lo = std::numeric_limits<float>::max(), hi = 0.0F;
  for (const Cell& cell : cells) {
    if (!window.holds(cell)) continue;
    const float d = window.at(cell);
    const float v = inv.forward(d);
    if (v > 0.0F) {
      lo = std::min(lo, d);
      hi = std::max(hi, d);
      best = std::max(best, v);
    }
  }
  if (best <= 0.0F) return result;
  result.z = inv.back(best);
  if (result.z <= 0.0F) return {};
  // Second pass, only for keypoints with depth: the nearest cell holding the winning value.
  float best_distance2 = std::numeric_limits<float>::max();
  for (const Cell& cell : cells) {
    if (!window.holds(cell) || inv.forward(window.at(cell)) != best) continue;
    best_distance2 = std::min(best_distance2, window.distance2(cell, pixel));
  }
  result.sample_distance_px = std::sqrt(best_distance2);
  result.spread = hi - lo;
  return result;
}

// A LiDAR sample under the kernel, and whether it belongs to the winning surface.
struct SurfaceSample {
  Cell cell;
  float d;
  bool on_surface;
};

// Scratch of lookup_surface_one, kept across the keypoints of one call (no allocation per keypoint).
struct SurfaceScratch {
  std::vector<SurfaceSample> samples;
  std::vector<std::size_t> frontier;
  std::vector<SurfaceSample> tall;  // the plane fit's taller window
};

// The fitted plane at the keypoint.
struct PlaneDepth {
  float z;         // m
  float gradient;  // |dz / d pixel|, m/px
};

// The plane through the surface's samples in a window fit.rows px tall, in inverse depth, at the
// keypoint (lookup_surface_depth); nullopt when they do not bracket the keypoint's row or are too few.
// min_cos_tilt: cos(fit.max_tilt_deg), once per call of lookup_surface_depth.
std::optional<PlaneDepth> fit_surface_plane(const cv::Mat_<float>& sparse, int radius, float surface_tolerance,
                                            const SurfacePlaneFit& fit, double min_cos_tilt,
                                            const Eigen::Vector2f& pixel, float surface_z, SurfaceScratch& scratch) {
  const int cx = static_cast<int>(std::floor(pixel.x() + 0.5F)), cy = static_cast<int>(std::floor(pixel.y() + 0.5F));
  auto& tall = scratch.tall;
  tall.clear();
  constexpr int kHalfWidth = 2;
  for (int dy = -fit.rows; dy <= fit.rows; ++dy) {
    if (cy + dy < 0 || cy + dy >= sparse.rows) continue;
    const float* row = sparse[cy + dy];
    for (int dx = -kHalfWidth; dx <= kHalfWidth; ++dx) {
      if (cx + dx < 0 || cx + dx >= sparse.cols || !(row[cx + dx] > 0.0F)) continue;
      tall.push_back({{dx, dy}, row[cx + dx], false});
    }
  }
  // grown from the kernel's sample nearest the surface's depth
  std::size_t seed = tall.size();
  float seed_difference = std::numeric_limits<float>::max();
  for (std::size_t i = 0; i < tall.size(); ++i) {
    if (std::abs(tall[i].cell.dx) + std::abs(tall[i].cell.dy) > radius) continue;
    const float difference = std::abs(tall[i].d - surface_z);
    if (difference < seed_difference) {
      seed_difference = difference;
      seed = i;
    }
  }
  if (seed == tall.size()) return std::nullopt;
  tall[seed].on_surface = true;
  auto& frontier = scratch.frontier;
  frontier.assign(1, seed);
  while (!frontier.empty()) {
    const SurfaceSample t = tall[frontier.back()];
    frontier.pop_back();
    for (std::size_t i = 0; i < tall.size(); ++i) {
      SurfaceSample& s = tall[i];
      if (s.on_surface || std::abs(s.cell.dx - t.cell.dx) > 2) continue;
      // rings lie a few rows apart: the step allowed grows with the rows between two samples
      const float rows = std::max(1.0F, 0.5F * static_cast<float>(std::abs(s.cell.dy - t.cell.dy)));
      if (std::abs(s.d - t.d) > surface_tolerance * rows * std::min(s.d, t.d)) continue;
      s.on_surface = true;
      frontier.push_back(i);
    }
  }
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double y_squares = 0.0;  // for the residual: sum r^2 = sum y^2 - plane . rhs at the least-squares plane
  float top = std::numeric_limits<float>::max(), bottom = std::numeric_limits<float>::lowest();
  int n = 0;
  for (const SurfaceSample& s : tall) {
    if (!s.on_surface) continue;
    const double ex = static_cast<double>(cx + s.cell.dx) - pixel.x(), ey = static_cast<double>(cy + s.cell.dy) - pixel.y();
    const Eigen::Vector3d j(1.0, ex, ey);
    const double y = 1.0 / static_cast<double>(s.d);
    normal += j * j.transpose();
    rhs += j * y;
    y_squares += y * y;
    top = std::min(top, static_cast<float>(ey));
    bottom = std::max(bottom, static_cast<float>(ey));
    ++n;
  }
  // interpolation only: samples above and below the keypoint, at least 2 rows apart
  if (n < 4 || top > 0.0F || bottom < 0.0F || bottom - top < 2.0F) return std::nullopt;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  const Eigen::Vector3d plane = ldlt.solve(rhs);  // inverse depth at the keypoint, per column, per row
  // Only on a surface below the camera and about level (SurfacePlaneFit): the road and ramps, which the
  // rings cross. The plane's normal in the camera's frame, from its inverse depth per pixel.
  const PinholeCamera& camera = fit.camera;
  const Eigen::Vector3d surface_normal(plane(1) * camera.fx, plane(2) * camera.fy,
                                       plane(0) - plane(1) * (pixel.x() - camera.cx) - plane(2) * (pixel.y() - camera.cy));
  if (!(surface_normal.y() > min_cos_tilt * surface_normal.norm())) return std::nullopt;
  // And only if the samples lie on that plane within what their rounding to pixel centres (uniform,
  // 1/12 px^2 per axis) and the range noise explain, at 3 sigma: a depth step the surface grew across
  // (far away the growth allows 10-15 % between rows 4-6 px apart) can look level, but is not a plane.
  const double squares = std::max(0.0, y_squares - plane.dot(rhs));
  const double noise = fit.range_sigma * plane(0) * plane(0);  // in inverse depth
  const double expected = (plane(1) * plane(1) + plane(2) * plane(2)) / 12.0 + noise * noise;
  if (squares / static_cast<double>(n - 3) > 9.0 * expected) return std::nullopt;
  const double inverse_z = plane(0);
  const double z = 1.0 / inverse_z;
  if (!std::isfinite(z) || z <= 0.0 || std::abs(z - surface_z) > 3.0 * surface_tolerance * surface_z) return std::nullopt;
  const double gradient = std::hypot(plane(1), plane(2)) * z * z;  // z = 1 / y: dz = -dy z^2
  return PlaneDepth{static_cast<float>(z), static_cast<float>(gradient)};
}

KeypointDepth lookup_surface_one(const cv::Mat_<float>& sparse, std::span<const Cell> cells, int radius,
                                 const Inversion& inv, float surface_tolerance, int step_px, const SurfacePlaneFit& fit,
                                 double min_cos_tilt, const Eigen::Vector2f& pixel, SurfaceScratch& scratch) {
  KeypointDepth result;
  const KernelWindow window(sparse, radius, pixel);
  if (window.empty()) return result;
  auto& samples = scratch.samples;
  samples.clear();
  std::size_t nearest = 0;
  for (const Cell& cell : cells) {
    if (!window.holds(cell)) continue;
    const float d = window.at(cell);
    if (!(inv.forward(d) > 0.0F)) continue;
    if (!samples.empty() && d < samples[nearest].d) nearest = samples.size();
    samples.push_back({cell, d, false});
  }
  if (samples.empty()) return result;
  // The winning surface grows from the nearest sample through samples within step_px columns and 2 rows
  // of it whose depths differ by at most surface_tolerance: a slanted road joins row by row, a jump to
  // the background does not.
  // Breadth-first: each sample joins once, so the cost is quadratic in the samples under the kernel.
  samples[nearest].on_surface = true;
  auto& frontier = scratch.frontier;
  frontier.assign(1, nearest);
  while (!frontier.empty()) {
    const SurfaceSample t = samples[frontier.back()];
    frontier.pop_back();
    for (std::size_t i = 0; i < samples.size(); ++i) {
      SurfaceSample& s = samples[i];
      if (s.on_surface || std::abs(s.cell.dx - t.cell.dx) > step_px || std::abs(s.cell.dy - t.cell.dy) > 2) continue;
      if (std::abs(s.d - t.d) > surface_tolerance * std::min(s.d, t.d)) continue;
      s.on_surface = true;
      frontier.push_back(i);
    }
  }
  float lo = std::numeric_limits<float>::max(), hi = 0.0F;
  double weights = 0.0, inverse_depths = 0.0;
  float nearest2 = std::numeric_limits<float>::max();
  for (const SurfaceSample& s : samples) {
    lo = std::min(lo, s.d);
    hi = std::max(hi, s.d);
    if (!s.on_surface) continue;
    const float distance2 = window.distance2(s.cell, pixel);
    nearest2 = std::min(nearest2, distance2);
    const double w = 1.0 / std::max(0.5, std::sqrt(static_cast<double>(distance2)));
    weights += w;
    inverse_depths += w / s.d;
  }
  result.z = static_cast<float>(weights / inverse_depths);
  if (fit.rows > 0) {
    if (const auto plane = fit_surface_plane(sparse, radius, surface_tolerance, fit, min_cos_tilt, pixel, result.z, scratch)) {
      result.z = plane->z;
      result.gradient = plane->gradient;
    }
  }
  result.sample_distance_px = std::sqrt(nearest2);
  result.spread = hi - lo;
  return result;
}

}  // namespace

void SurfacePlaneFit::validate() const {
  require(rows >= 0, "lidar surface fit rows", ">= 0 px (0 = off)");
  if (rows > 0) camera.validate();
  require(max_tilt_deg > 0.0 && max_tilt_deg < 90.0, "lidar.surface_fit_max_tilt_deg", "0 .. 90 deg");
  require(range_sigma > 0.0, "lidar.range_sigma", "> 0 m");
}

void lookup_surface_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, float surface_tolerance,
                          std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out,
                          const SurfacePlaneFit& fit, int step_px) {
  options.validate();
  require(surface_tolerance >= 0.0F && surface_tolerance < 1.0F, "lidar.surface_tolerance", "a fraction in [0, 1)");
  require(step_px >= 1 && step_px <= 15, "lidar.surface_step_px", "1 .. 15 px");
  fit.validate();
  CV_Assert(out.size() == pixels.size());
  const Kernel kernel = options.kernel();
  const std::vector<Cell> cells = kernel_cells(kernel);
  const Inversion inv(options.max_depth);
  const double min_cos_tilt = std::cos(fit.max_tilt_deg * std::numbers::pi / 180.0);
  SurfaceScratch scratch;
  scratch.samples.reserve(cells.size());
  scratch.frontier.reserve(cells.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    out[i] = lookup_surface_one(sparse, cells, kernel.radius(), inv, surface_tolerance, step_px, fit, min_cos_tilt,
                                pixels[i], scratch);
  }
}

KeypointDepth lookup_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, const Eigen::Vector2f& pixel) {
  KeypointDepth out;
  lookup_depth(sparse, options, std::span<const Eigen::Vector2f>(&pixel, 1), std::span<KeypointDepth>(&out, 1));
  return out;
}

void lookup_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, std::span<const Eigen::Vector2f> pixels,
                  std::span<KeypointDepth> out) {
  options.validate();
  CV_Assert(out.size() == pixels.size());
  const Kernel kernel = options.kernel();
  const std::vector<Cell> cells = kernel_cells(kernel);
  const Inversion inv(options.max_depth);
  for (std::size_t i = 0; i < pixels.size(); ++i) out[i] = lookup_one(sparse, cells, kernel.radius(), inv, pixels[i]);
}

int remove_occluded_samples(cv::Mat_<float>& sparse, int radius, float ratio, cv::Mat_<float>& scratch) {
  require(radius >= 0, "lidar.occlusion radius", ">= 0 px");
  require(ratio > 1.0F, "lidar.occlusion_ratio", "> 1");
  if (radius == 0 || sparse.empty()) return 0;
  // Only the rows the scan covers (on KITTI the top third of the image has no return) and the window
  // around them: outside, every pixel is empty either way.
  int first = sparse.rows, last = -1;
  for (int y = 0; y < sparse.rows; ++y) {
    const float* row = sparse[y];
    if (std::any_of(row, row + sparse.cols, [](float v) { return v > 0.0F; })) {
      first = std::min(first, y);
      last = y;
    }
  }
  if (last < 0) return 0;
  const int top = std::max(0, first - radius), bottom = std::min(sparse.rows, last + radius + 1);
  // The nearest sample around every pixel: a grey erosion with empty pixels as +infinity. The loops are
  // branch-free so that they vectorise; the scratch image is reused from frame to frame.
  const float empty = std::numeric_limits<float>::max();
  scratch.create(bottom - top, sparse.cols);
  for (int y = top; y < bottom; ++y) {
    const float* in = sparse[y];
    float* out = scratch[y - top];
    for (int x = 0; x < sparse.cols; ++x) out[x] = in[x] > 0.0F ? in[x] : empty;
  }
  cv::erode(scratch, scratch, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * radius + 1, 2 * radius + 1)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(empty));
  int dropped = 0;
  for (int y = top; y < bottom; ++y) {
    float* row = sparse[y];
    const float* nearest = scratch[y - top];
    for (int x = 0; x < sparse.cols; ++x) {
      const bool drop = row[x] > ratio * nearest[x];  // false for an empty pixel (0 > a positive depth)
      dropped += drop ? 1 : 0;
      row[x] = drop ? 0.0F : row[x];
    }
  }
  return dropped;
}

int remove_occluded_samples(cv::Mat_<float>& sparse, int radius, float ratio) {
  cv::Mat_<float> scratch;
  return remove_occluded_samples(sparse, radius, ratio, scratch);
}

int occlusion_radius_px(double fx, double window_deg) {
  require(fx > 0.0, "occlusion_radius_px fx", "> 0 px");
  require(window_deg >= 0.0 && window_deg < 90.0, "lidar.occlusion_window_deg", "in [0, 90) deg");
  if (window_deg == 0.0) return 0;
  return std::max(1, static_cast<int>(std::lround(fx * std::tan(window_deg * std::numbers::pi / 180.0))));
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
