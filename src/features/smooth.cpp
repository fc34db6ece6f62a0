#include "smooth.hpp"

#include "simd.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>


namespace rgbl::detail {

namespace {

#if defined(RGBL_HAVE_AVX2_PATH)
// OpenCV's 8-bit Gaussian (cv::GaussianBlur's fixed-point path): the kernel k (sum 256) applied along
// rows gives H in [0, 65280] exactly, then along columns V = sum k_j H_j, and the output is
// (V + 2^15) >> 16. With H = 256 Hh + Hl (Hh, Hl < 256) both column sums A = sum k_j Hh_j and
// B = sum k_j Hl_j stay below 2^16, and (256 A + B + 2^15) >> 16 = (A + (B >> 8) + 128) >> 8, so the
// whole filter runs in 16-bit lanes.
constexpr int kTap0 = 56, kTap1 = 48, kTap2 = 34, kTap3 = 18;  // centre outwards

__attribute__((target("avx2"))) inline __m256i widen(const std::uint8_t* p) {
  return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

__attribute__((target("avx2"))) inline __m256i load(const std::uint16_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// The symmetric 7-tap sum of c[-3..3] in 16-bit lanes (exact: the true sums stay below 2^16).
__attribute__((target("avx2"))) inline __m256i taps(__m256i m3, __m256i m2, __m256i m1, __m256i c, __m256i p1,
                                                    __m256i p2, __m256i p3) {
  __m256i s = _mm256_mullo_epi16(c, _mm256_set1_epi16(kTap0));
  s = _mm256_add_epi16(s, _mm256_mullo_epi16(_mm256_add_epi16(m1, p1), _mm256_set1_epi16(kTap1)));
  s = _mm256_add_epi16(s, _mm256_mullo_epi16(_mm256_add_epi16(m2, p2), _mm256_set1_epi16(kTap2)));
  return _mm256_add_epi16(s, _mm256_mullo_epi16(_mm256_add_epi16(m3, p3), _mm256_set1_epi16(kTap3)));
}

// One source row, padded by 3 reflected pixels on each side, into its (hi, lo) halves.
__attribute__((target("avx2"))) void row_pass(const std::uint8_t* padded, int width, std::uint16_t* hi,
                                              std::uint16_t* lo) {
  const __m256i low_byte = _mm256_set1_epi16(0xFF);
  for (int x = 0;;) {
    if (x + 16 > width) x = width - 16;  // the tail as one overlapping block
    const std::uint8_t* p = padded + x;  // p[3] is pixel x
    const __m256i h = taps(widen(p), widen(p + 1), widen(p + 2), widen(p + 3), widen(p + 4), widen(p + 5), widen(p + 6));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hi + x), _mm256_srli_epi16(h, 8));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(lo + x), _mm256_and_si256(h, low_byte));
    if (x + 16 >= width) break;
    x += 16;
  }
}

// hi[j], lo[j]: the row pass of source row y + j - 3 (reflected).
__attribute__((target("avx2"))) void column_pass(const std::uint16_t* const* hi, const std::uint16_t* const* lo,
                                                 int width, std::uint8_t* out) {
  const __m256i round = _mm256_set1_epi16(128);
  for (int x = 0;;) {
    if (x + 16 > width) x = width - 16;
    const __m256i a = taps(load(hi[0] + x), load(hi[1] + x), load(hi[2] + x), load(hi[3] + x), load(hi[4] + x),
                           load(hi[5] + x), load(hi[6] + x));
    const __m256i b = taps(load(lo[0] + x), load(lo[1] + x), load(lo[2] + x), load(lo[3] + x), load(lo[4] + x),
                           load(lo[5] + x), load(lo[6] + x));
    const __m256i v = _mm256_srli_epi16(_mm256_add_epi16(_mm256_add_epi16(a, _mm256_srli_epi16(b, 8)), round), 8);
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi16(v, v), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(packed));
    if (x + 16 >= width) break;
    x += 16;
  }
}

__attribute__((target("avx2"))) void smooth_avx2(const cv::Mat& src, cv::Mat& dst, std::vector<std::uint8_t>& padded,
                                                 std::vector<std::uint16_t>& ring) {
  const int w = src.cols, h = src.rows;
  const auto stride = static_cast<std::size_t>(w) + 16;
  // ring: the row passes of 8 source rows (7 in use), high bytes then low bytes
  padded.resize(static_cast<std::size_t>(w) + 6 + 32);
  ring.resize(2 * 8 * stride);
  const auto hi_row = [&](int y) { return ring.data() + static_cast<std::size_t>(y % 8) * stride; };
  const auto lo_row = [&](int y) { return ring.data() + (8 + static_cast<std::size_t>(y % 8)) * stride; };
  const auto reflect = [&](int y) { return y < 0 ? -y : (y >= h ? 2 * h - 2 - y : y); };
  int done = 0;  // source rows [0, done) have their row pass in the ring
  const auto row_pass_through = [&](int last) {
    for (; done <= last; ++done) {
      const std::uint8_t* s = src.ptr<std::uint8_t>(done);
      std::memcpy(padded.data() + 3, s, static_cast<std::size_t>(w));
      for (int k = 1; k <= 3; ++k) {
        padded[static_cast<std::size_t>(3 - k)] = s[k];
        padded[static_cast<std::size_t>(w + 2 + k)] = s[w - 1 - k];
      }
      row_pass(padded.data(), w, hi_row(done), lo_row(done));
    }
  };
  const std::uint16_t* hi[7];
  const std::uint16_t* lo[7];
  for (int y = 0; y < h; ++y) {
    row_pass_through(std::min(h - 1, y + 3));
    for (int j = 0; j < 7; ++j) {
      const int r = reflect(y + j - 3);
      hi[j] = hi_row(r);
      lo[j] = lo_row(r);
    }
    column_pass(hi, lo, w, dst.ptr<std::uint8_t>(y));
  }
}
#endif

}  // namespace

void smooth_for_brief(const cv::Mat& src, cv::Mat& dst, int size, double sigma, std::vector<std::uint8_t>& padded,
                      std::vector<std::uint16_t>& rows, bool allow_fast) {
#if defined(RGBL_HAVE_AVX2_PATH)
  // The rows kept are the last 8 (with row y + 3 computed, the oldest needed is y - 3, or a reflected
  // row between them); reflection needs 4 rows, the overlapping tail block 16 columns.
  if (allow_fast && size == 7 && sigma == 2.0 && src.type() == CV_8UC1 && src.cols >= 16 && src.rows >= 4 &&
      cpu_has_avx2()) {
    if (dst.data == src.data) dst.release();  // create() would keep the shared buffer
    dst.create(src.size(), CV_8UC1);            // no-op when dst already fits
    smooth_avx2(src, dst, padded, rows);
    return;
  }
#else
  (void)allow_fast;
  (void)padded;
  (void)rows;
#endif
  cv::GaussianBlur(src, dst, cv::Size(size, size), sigma, sigma, cv::BORDER_REFLECT_101);
}

}  // namespace rgbl::detail
