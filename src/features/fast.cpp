#include "fast.hpp"

#include <algorithm>
#include <array>

namespace rgbl::detail {

namespace {

// The Bresenham circle of radius 3, clockwise from the top.
constexpr std::array<std::array<int, 2>, 16> kCircle = {{{0, -3}, {1, -3}, {2, -2}, {3, -1}, {3, 0}, {3, 1},
                                                         {2, 2}, {1, 3}, {0, 3}, {-1, 3}, {-2, 2}, {-3, 1},
                                                         {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}}};

// Score of one pixel: with b[k] = max(p_k - c, 0) and d[k] = max(c - p_k, 0), the best arc of 9 has
// min over the arc of b (or d) = m; the pixel is a corner at every t < m, so its score is m - 1.
inline int pixel_score(const std::uint8_t* centre, const std::array<int, 16>& offsets) {
  const int c = centre[0];
  std::array<int, 25> b{}, d{};
  for (std::size_t k = 0; k < 16; ++k) {
    const int p = centre[offsets[k]];
    b[k] = std::max(p - c, 0);
    d[k] = std::max(c - p, 0);
  }
  for (std::size_t k = 16; k < 25; ++k) {
    b[k] = b[k - 16];
    d[k] = d[k - 16];
  }
  int best = 0;
  for (std::size_t k = 0; k < 16; ++k) {
    int mb = b[k], md = d[k];
    for (std::size_t j = 1; j < 9; ++j) {
      mb = std::min(mb, b[k + j]);
      md = std::min(md, d[k + j]);
    }
    best = std::max(best, std::max(mb, md));
  }
  return best - 1;
}

#if defined(__SSE2__)
inline __m128i load(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }

// Scores of 16 consecutive pixels (0 where not a corner at `threshold`), written to `out`.
inline void block_scores(const std::uint8_t* centre, const std::array<int, 16>& offsets, int threshold,
                         std::uint8_t* out) {
  const __m128i c = load(centre);
  const __m128i t1 = _mm_set1_epi8(static_cast<char>(threshold + 1));
  const __m128i zero = _mm_setzero_si128();
  // Quick rejection: a 9-arc covers two consecutive compass points (0, 4, 8, 12) of the circle.
  __m128i b[16], d[16];
  for (int k = 0; k < 16; k += 4) {
    const __m128i p = load(centre + offsets[static_cast<std::size_t>(k)]);
    b[k] = _mm_subs_epu8(p, c);
    d[k] = _mm_subs_epu8(c, p);
  }
  auto ge = [&](__m128i v) { return _mm_cmpeq_epi8(_mm_max_epu8(v, t1), v); };  // v >= threshold + 1
  const __m128i b0 = ge(b[0]), b4 = ge(b[4]), b8 = ge(b[8]), b12 = ge(b[12]);
  const __m128i d0 = ge(d[0]), d4 = ge(d[4]), d8 = ge(d[8]), d12 = ge(d[12]);
  const __m128i possible = _mm_or_si128(
      _mm_or_si128(_mm_or_si128(_mm_and_si128(b0, b4), _mm_and_si128(b4, b8)),
                   _mm_or_si128(_mm_and_si128(b8, b12), _mm_and_si128(b12, b0))),
      _mm_or_si128(_mm_or_si128(_mm_and_si128(d0, d4), _mm_and_si128(d4, d8)),
                   _mm_or_si128(_mm_and_si128(d8, d12), _mm_and_si128(d12, d0))));
  if (_mm_movemask_epi8(possible) == 0) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), zero);
    return;
  }
  for (int k = 0; k < 16; ++k) {
    if (k % 4 == 0) continue;
    const __m128i p = load(centre + offsets[static_cast<std::size_t>(k)]);
    b[k] = _mm_subs_epu8(p, c);
    d[k] = _mm_subs_epu8(c, p);
  }
  // The best minimum over the 16 cyclic windows of 9, two windows at a time: for even k, windows k
  // and k + 1 share v[k+1..k+8], so max(min over window k, min over window k + 1) =
  // min(min(v[k+1..k+8]), max(v[k], v[k+9])). The shared 8-minima at odd starts come by doubling
  // (2, 4, 8) from odd starts only: 48 min/max per side instead of 80.
  auto best_arc = [](const __m128i* v) {
    __m128i m2[16], m4[16];
    for (int j = 1; j < 16; j += 2) m2[j] = _mm_min_epu8(v[j], v[(j + 1) & 15]);
    for (int j = 1; j < 16; j += 2) m4[j] = _mm_min_epu8(m2[j], m2[(j + 2) & 15]);
    __m128i best = _mm_setzero_si128();
    for (int k = 0; k < 16; k += 2) {
      const __m128i m8 = _mm_min_epu8(m4[k + 1], m4[(k + 5) & 15]);
      best = _mm_max_epu8(best, _mm_min_epu8(m8, _mm_max_epu8(v[k], v[(k + 9) & 15])));
    }
    return best;
  };
  const __m128i s = _mm_max_epu8(best_arc(b), best_arc(d));
  // Corner where s >= threshold + 1; its score is s - 1 (>= threshold >= 1, so never 0).
  const __m128i corner = ge(s);
  const __m128i score = _mm_and_si128(corner, _mm_subs_epu8(s, _mm_set1_epi8(1)));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out), score);
}
#endif

#if defined(RGBL_HAVE_AVX2_PATH)
// The same computation as block_scores on 32 pixels per step, compiled for AVX2 only in this function
// and chosen at run time, so the build needs no -march flag. Without block_scores' quick rejection:
// on real frames (KITTI) whether a block of 32 has a candidate is a coin flip to the branch
// predictor, and the mispredictions cost more than scoring every block (orb/rgbl 4 % faster).
__attribute__((target("avx2"))) void row_scores_avx2(const std::uint8_t* row, int begin, int end,
                                                     const std::array<int, 16>& offsets, int threshold,
                                                     std::uint8_t* out) {
  const __m256i t1 = _mm256_set1_epi8(static_cast<char>(threshold + 1));
  const __m256i one = _mm256_set1_epi8(1);
  int x = begin;
  for (;;) {
    if (x + 32 > end) {
      if (x == end) break;
      x = end - 32;  // the tail as one overlapping block
    }
    const std::uint8_t* centre = row + x;
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(centre));
    __m256i p[16];  // the circle's pixels
    for (int k = 0; k < 16; ++k) {
      p[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(centre + offsets[static_cast<std::size_t>(k)]));
    }
    std::uint8_t* dst = out + (x - begin);
    // On the circle's pixels themselves: the min over an arc of (p - c)+ is (min over the arc of p - c)+,
    // and the min of (c - p)+ is (c - max over the arc of p)+, so the brightest arc's minimum and the
    // darkest arc's maximum give the score with two subtractions in all. Two windows of 9 at a time as
    // in block_scores (odd starts only).
    __m256i lo2[16], lo4[16], hi2[16], hi4[16];
    for (int j = 1; j < 16; j += 2) {
      lo2[j] = _mm256_min_epu8(p[j], p[(j + 1) & 15]);
      hi2[j] = _mm256_max_epu8(p[j], p[(j + 1) & 15]);
    }
    for (int j = 1; j < 16; j += 2) {
      lo4[j] = _mm256_min_epu8(lo2[j], lo2[(j + 2) & 15]);
      hi4[j] = _mm256_max_epu8(hi2[j], hi2[(j + 2) & 15]);
    }
    __m256i brightest = _mm256_setzero_si256(), darkest = _mm256_set1_epi8(static_cast<char>(0xFF));
    for (int k = 0; k < 16; k += 2) {
      const __m256i lo8 = _mm256_min_epu8(lo4[k + 1], lo4[(k + 5) & 15]);
      const __m256i hi8 = _mm256_max_epu8(hi4[k + 1], hi4[(k + 5) & 15]);
      brightest = _mm256_max_epu8(brightest, _mm256_min_epu8(lo8, _mm256_max_epu8(p[k], p[(k + 9) & 15])));
      darkest = _mm256_min_epu8(darkest, _mm256_max_epu8(hi8, _mm256_min_epu8(p[k], p[(k + 9) & 15])));
    }
    const __m256i best = _mm256_max_epu8(_mm256_subs_epu8(brightest, c), _mm256_subs_epu8(c, darkest));
    const __m256i corner = _mm256_cmpeq_epi8(_mm256_max_epu8(best, t1), best);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), _mm256_and_si256(corner, _mm256_subs_epu8(best, one)));
    x += 32;
  }
}

#endif

#if defined(RGBL_HAVE_AVX2_PATH)
// The same as row_scores_avx2 on 64 pixels per step with AVX-512BW (also without the quick
// rejection: orb/rgbl 2.5 % faster without it).
__attribute__((target("avx512bw"))) void row_scores_avx512(const std::uint8_t* row, int begin, int end,
                                                           const std::array<int, 16>& offsets, int threshold,
                                                           std::uint8_t* out) {
  const __m512i t1 = _mm512_set1_epi8(static_cast<char>(threshold + 1));
  const __m512i one = _mm512_set1_epi8(1);
  int x = begin;
  for (;;) {
    if (x + 64 > end) {
      if (x == end) break;
      x = end - 64;  // the tail as one overlapping block
    }
    const std::uint8_t* centre = row + x;
    const __m512i c = _mm512_loadu_si512(centre);
    __m512i p[16];
    for (int k = 0; k < 16; ++k) p[k] = _mm512_loadu_si512(centre + offsets[static_cast<std::size_t>(k)]);
    std::uint8_t* dst = out + (x - begin);
    __m512i lo2[16], lo4[16], hi2[16], hi4[16];
    for (int j = 1; j < 16; j += 2) {
      lo2[j] = _mm512_min_epu8(p[j], p[(j + 1) & 15]);
      hi2[j] = _mm512_max_epu8(p[j], p[(j + 1) & 15]);
    }
    for (int j = 1; j < 16; j += 2) {
      lo4[j] = _mm512_min_epu8(lo2[j], lo2[(j + 2) & 15]);
      hi4[j] = _mm512_max_epu8(hi2[j], hi2[(j + 2) & 15]);
    }
    __m512i brightest = _mm512_setzero_si512(), darkest = _mm512_set1_epi8(static_cast<char>(0xFF));
    for (int k = 0; k < 16; k += 2) {
      const __m512i lo8 = _mm512_min_epu8(lo4[k + 1], lo4[(k + 5) & 15]);
      const __m512i hi8 = _mm512_max_epu8(hi4[k + 1], hi4[(k + 5) & 15]);
      brightest = _mm512_max_epu8(brightest, _mm512_min_epu8(lo8, _mm512_max_epu8(p[k], p[(k + 9) & 15])));
      darkest = _mm512_min_epu8(darkest, _mm512_max_epu8(hi8, _mm512_min_epu8(p[k], p[(k + 9) & 15])));
    }
    const __m512i best = _mm512_max_epu8(_mm512_subs_epu8(brightest, c), _mm512_subs_epu8(c, darkest));
    _mm512_storeu_si512(dst, _mm512_maskz_subs_epu8(_mm512_cmpge_epu8_mask(best, t1), best, one));
    x += 64;
  }
}

#endif

}  // namespace

bool cpu_has_avx2() {
#if defined(RGBL_HAVE_AVX2_PATH)
  // (every CPU with AVX2 has POPCNT, which the AVX2 suppression uses; checked all the same)
  static const bool has = __builtin_cpu_supports("avx2") != 0 && __builtin_cpu_supports("popcnt") != 0;
  return has;
#else
  return false;
#endif
}

bool cpu_has_avx512bw() {
#if defined(RGBL_HAVE_AVX2_PATH) && !defined(RGBL_NO_AVX512)
  static const bool has = __builtin_cpu_supports("avx512bw") != 0;
  return has;
#else
  return false;
#endif
}

namespace {

std::array<int, 16> circle_offsets(const cv::Mat& img) {
  const auto step = static_cast<int>(img.step1());
  std::array<int, 16> offsets{};
  for (std::size_t k = 0; k < 16; ++k) offsets[k] = kCircle[k][1] * step + kCircle[k][0];
  return offsets;
}

// Scores of image row y over the region's columns into out[0, region.width).
void score_row(const cv::Mat& img, cv::Rect region, int y, const std::array<int, 16>& offsets, int threshold,
               std::uint8_t* out, SimdWidth widest) {
  const std::uint8_t* row = img.ptr<std::uint8_t>(y);
  int x = region.x;
  const int end = region.x + region.width;
#if !defined(RGBL_HAVE_AVX2_PATH)
  (void)widest;
#else
  if (widest == SimdWidth::avx512 && region.width >= 64 && cpu_has_avx512bw()) {
    row_scores_avx512(row, x, end, offsets, threshold, out);
    return;
  }
  if (widest != SimdWidth::sse2 && region.width >= 32 && cpu_has_avx2()) {
    row_scores_avx2(row, x, end, offsets, threshold, out);
    return;
  }
#endif
#if defined(__SSE2__)
  if (region.width >= 16) {
    for (; x + 16 <= end; x += 16) block_scores(row + x, offsets, threshold, out + (x - region.x));
    // The tail as one more (overlapping) block: it rewrites the same values.
    if (x < end) block_scores(row + end - 16, offsets, threshold, out + (end - 16 - region.x));
    x = end;
  }
#endif
  for (; x < end; ++x) {
    const int s = pixel_score(row + x, offsets);
    out[x - region.x] = static_cast<std::uint8_t>(s >= threshold ? s : 0);
  }
}

#if defined(RGBL_HAVE_AVX2_PATH)
// suppress_row's test on the 32 map entries from `mid` (and their neighbours): bit i is set where entry
// i is a corner.
__attribute__((target("avx2"))) inline std::uint32_t local_maxima_avx2(const std::uint8_t* up, const std::uint8_t* mid,
                                                                      const std::uint8_t* down) {
  const __m256i s = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(mid));
  auto mask = ~static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(s, _mm256_setzero_si256())));
  if (mask == 0) return 0;
  const auto n = [](const std::uint8_t* q) { return q; };
  __m256i keep = _mm256_set1_epi8(static_cast<char>(0xFF));
  for (const std::uint8_t* q : {n(up - 1), n(up), n(up + 1), n(mid - 1)}) {  // s > neighbour
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q));
    keep = _mm256_and_si256(keep, _mm256_andnot_si256(_mm256_cmpeq_epi8(s, v), _mm256_cmpeq_epi8(_mm256_max_epu8(s, v), s)));
  }
  for (const std::uint8_t* q : {n(mid + 1), n(down - 1), n(down), n(down + 1)}) {  // s >= neighbour
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q));
    keep = _mm256_and_si256(keep, _mm256_cmpeq_epi8(_mm256_max_epu8(s, v), s));
  }
  return mask & static_cast<std::uint32_t>(_mm256_movemask_epi8(keep));
}

// Appends the corners of one step's mask (bit i: map entry x + i of row `mid`) at corners[count] and
// returns the new count. The first four are written unconditionally (slots past the step's last
// corner are overwritten by the next step, or dropped): a loop over the mask's bits would end in a
// mispredicted branch at nearly every step, and a step rarely has more than four corners.
__attribute__((target("popcnt"))) inline std::size_t emit_corners(std::uint64_t mask, int x, cv::Rect region, int y,
                                                                  const std::uint8_t* mid, FastCorner* corners,
                                                                  std::size_t count) {
  FastCorner* out = corners + count;
  count += static_cast<std::size_t>(__builtin_popcountll(mask));
  for (int j = 0; j < 4; ++j) {
    // with no corner left this gives 63, a readable entry (the row's or its padding); the slot is not
    // counted
    const int bit = __builtin_ctzll(mask | (std::uint64_t{1} << 63U));
    out[j] = {region.x + x + bit - 1, y, mid[x + bit]};
    mask &= mask - 1U;
  }
  out += 4;
  while (mask != 0) {
    const int bit = __builtin_ctzll(mask);
    mask &= mask - 1U;
    *out++ = {region.x + x + bit - 1, y, mid[x + bit]};
  }
  return count;
}

// The vector suppressions write the row's corners from corners[count] on and return the new count;
// the caller keeps room for region.width / 2 + 8 more (two maxima are never neighbours in a row, and
// up to 3 slots past the last corner are written). The AVX2 one takes 64 entries a step as two halves
// (the rows need 64 readable bytes of padding, as for AVX-512), so each step's corners come out of
// one 64-bit mask.
__attribute__((target("avx2,popcnt"))) std::size_t suppress_row_avx2(const std::uint8_t* up, const std::uint8_t* mid,
                                                                   const std::uint8_t* down, cv::Rect region, int y,
                                                                   FastCorner* corners, std::size_t count) {
  for (int x = 1; x <= region.width; x += 64) {
    auto mask = std::uint64_t{local_maxima_avx2(up + x, mid + x, down + x)} |
                std::uint64_t{local_maxima_avx2(up + x + 32, mid + x + 32, down + x + 32)} << 32U;
    if (region.width - x + 1 < 64) mask &= (std::uint64_t{1} << static_cast<unsigned>(region.width - x + 1)) - 1U;
    count = emit_corners(mask, x, region, y, mid, corners, count);
  }
  return count;
}
#endif

#if defined(RGBL_HAVE_AVX2_PATH)
// suppress_row on 64 map entries per step with AVX-512BW.
__attribute__((target("avx512bw,popcnt"))) std::size_t suppress_row_avx512(const std::uint8_t* up, const std::uint8_t* mid,
                                                                          const std::uint8_t* down, cv::Rect region,
                                                                          int y, FastCorner* corners, std::size_t count) {
  for (int x = 1; x <= region.width; x += 64) {
    const __m512i s = _mm512_loadu_si512(mid + x);
    auto mask = static_cast<std::uint64_t>(_mm512_test_epi8_mask(s, s));  // nonzero entries
    if (mask == 0) continue;
    mask &= _mm512_cmpgt_epu8_mask(s, _mm512_loadu_si512(up + x - 1)) & _mm512_cmpgt_epu8_mask(s, _mm512_loadu_si512(up + x)) &
            _mm512_cmpgt_epu8_mask(s, _mm512_loadu_si512(up + x + 1)) & _mm512_cmpgt_epu8_mask(s, _mm512_loadu_si512(mid + x - 1)) &
            _mm512_cmpge_epu8_mask(s, _mm512_loadu_si512(mid + x + 1)) & _mm512_cmpge_epu8_mask(s, _mm512_loadu_si512(down + x - 1)) &
            _mm512_cmpge_epu8_mask(s, _mm512_loadu_si512(down + x)) & _mm512_cmpge_epu8_mask(s, _mm512_loadu_si512(down + x + 1));
    if (region.width - x + 1 < 64) mask &= (std::uint64_t{1} << static_cast<unsigned>(region.width - x + 1)) - 1U;
    count = emit_corners(mask, x, region, y, mid, corners, count);
  }
  return count;
}
#endif

// Appends the 3x3 maxima of map row `mid` (rows of width + 2 entries with a zero column at each end,
// 16 entries of readable padding after; detect_fast's ring has 64) as corners of image row y.
void suppress_row(const std::uint8_t* up, const std::uint8_t* mid, const std::uint8_t* down, cv::Rect region, int y,
                  std::vector<FastCorner>& corners) {
#if defined(__SSE2__)
  // 16 map entries at a time, the local-maximum test done on all of them with unsigned byte
  // compares (a > b as max(a, b) == a and a != b).
  for (int x = 1; x <= region.width; x += 16) {
    const __m128i s = load(mid + x);
    const __m128i zero = _mm_setzero_si128();
    auto mask = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(s, zero))) ^ 0xFFFFU;
    if (mask == 0) continue;
    auto ge = [&](const std::uint8_t* p) { return _mm_cmpeq_epi8(_mm_max_epu8(s, load(p)), s); };
    auto gt = [&](const std::uint8_t* p) {
      const __m128i n = load(p);
      return _mm_andnot_si128(_mm_cmpeq_epi8(s, n), _mm_cmpeq_epi8(_mm_max_epu8(s, n), s));
    };
    const __m128i keep = _mm_and_si128(
        _mm_and_si128(_mm_and_si128(gt(up + x - 1), gt(up + x)), _mm_and_si128(gt(up + x + 1), gt(mid + x - 1))),
        _mm_and_si128(_mm_and_si128(ge(mid + x + 1), ge(down + x - 1)), _mm_and_si128(ge(down + x), ge(down + x + 1))));
    mask &= static_cast<unsigned>(_mm_movemask_epi8(keep));
    if (region.width - x + 1 < 16) mask &= (1U << static_cast<unsigned>(region.width - x + 1)) - 1U;
    while (mask != 0) {
      const int bit = __builtin_ctz(mask);
      mask &= mask - 1U;
      corners.push_back({region.x + x + bit - 1, y, mid[x + bit]});
    }
  }
#else
  for (int x = 1; x <= region.width; ++x) {
    const int s = mid[x];
    if (s != 0 && s > up[x - 1] && s > up[x] && s > up[x + 1] && s > mid[x - 1] && s >= mid[x + 1] &&
        s >= down[x - 1] && s >= down[x] && s >= down[x + 1]) {
      corners.push_back({region.x + x - 1, y, s});
    }
  }
#endif
}

}  // namespace

void fast_score_map(const cv::Mat& img, cv::Rect region, int threshold, std::vector<std::uint8_t>& scores,
                    SimdWidth widest) {
  const int map_w = region.width + 2;
  // The whole level's map, for tests (detect_fast keeps only a ring of rows); 16 bytes of padding as
  // suppress_row expects.
  scores.assign(static_cast<std::size_t>(map_w) * static_cast<std::size_t>(region.height + 2) + 16, 0);
  const auto offsets = circle_offsets(img);
  for (int y = region.y; y < region.y + region.height; ++y) {
    std::uint8_t* out = scores.data() + static_cast<std::size_t>(y - region.y + 1) * static_cast<std::size_t>(map_w) + 1;
    score_row(img, region, y, offsets, threshold, out, widest);
  }
}

void detect_fast(const cv::Mat& img, cv::Rect region, int threshold, std::vector<std::uint8_t>& scores,
                 std::vector<FastCorner>& corners, SimdWidth widest) {
  corners.clear();
  if (region.width <= 0 || region.height <= 0) return;
  // The map's rows in a ring of four, so each row is suppressed while its neighbours are still in L1,
  // instead of writing and re-reading a map of the whole level; scoring runs two rows ahead, so no
  // row is read right after it was written (its unaligned reads would wait on the stores).
  const auto map_w = static_cast<std::size_t>(region.width) + 2;
  scores.assign(4 * map_w + 64, 0);
  const auto offsets = circle_offsets(img);
  const auto ring = [&](int map_row) { return scores.data() + static_cast<std::size_t>(map_row % 4) * map_w; };
  // map row m holds image row region.y + m - 1; rows 0 and height + 1 are zero
  const auto produce = [&](int m) {
    if (m >= 1 && m <= region.height) {
      score_row(img, region, region.y + m - 1, offsets, threshold, ring(m) + 1, widest);
    } else if (m == region.height + 1) {
      std::fill(ring(m), ring(m) + map_w, std::uint8_t{0});
    }
  };
  produce(1);
  produce(2);
#if defined(RGBL_HAVE_AVX2_PATH)
  const bool use_avx512 = widest == SimdWidth::avx512 && cpu_has_avx512bw();
  const bool use_avx2 = !use_avx512 && widest != SimdWidth::sse2 && cpu_has_avx2();
  // The vector paths write corners in place (see emit_corners); the size is set once at the end.
  const auto room = static_cast<std::size_t>(region.width) / 2 + 8;
  std::size_t count = 0;
#endif
  for (int r = 1; r <= region.height; ++r) {
    produce(r + 2);
#if defined(RGBL_HAVE_AVX2_PATH)
    if (use_avx512 || use_avx2) {
      if (corners.size() < count + room) corners.resize(std::max(2 * corners.size(), count + room));
      count = use_avx512
                  ? suppress_row_avx512(ring(r - 1), ring(r), ring(r + 1), region, region.y + r - 1, corners.data(), count)
                  : suppress_row_avx2(ring(r - 1), ring(r), ring(r + 1), region, region.y + r - 1, corners.data(), count);
      continue;
    }
#endif
    suppress_row(ring(r - 1), ring(r), ring(r + 1), region, region.y + r - 1, corners);
  }
#if defined(RGBL_HAVE_AVX2_PATH)
  if (use_avx512 || use_avx2) corners.resize(count);
#endif
}

}  // namespace rgbl::detail
