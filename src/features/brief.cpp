#include "brief.hpp"

#include "simd.hpp"

#include <array>


namespace rgbl::detail {

namespace {

inline int round_away(float v) { return static_cast<int>(v + (v >= 0.0F ? 0.5F : -0.5F)); }

#if defined(__SSE2__)
// round half away from zero: truncate v + copysign(0.5, v) (for v = -0 both give 0)
inline __m128 round_away_sse2(__m128 v) {
  const __m128 half = _mm_set1_ps(0.5F), sign = _mm_set1_ps(-0.0F);
  return _mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_add_ps(v, _mm_or_ps(half, _mm_and_ps(v, sign)))));
}
#endif

#if defined(RGBL_HAVE_AVX2_PATH)
__attribute__((target("avx2"))) inline __m256 round_away_avx2(__m256 v) {
  const __m256 half = _mm256_set1_ps(0.5F), sign = _mm256_set1_ps(-0.0F);
  // truncation in float (the same as to int and back for these small values)
  return _mm256_round_ps(_mm256_add_ps(v, _mm256_or_ps(half, _mm256_and_ps(v, sign))), _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
}

// 8 pairs at a time; returns how many pairs it did.
__attribute__((target("avx2"))) std::size_t rotate_avx2(const float* soa, std::size_t n, float sa, float ca, int step,
                                                        int* offsets) {
  const __m256 vsa = _mm256_set1_ps(sa), vca = _mm256_set1_ps(ca);
  const __m256 vstep = _mm256_set1_ps(static_cast<float>(step));
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    for (std::size_t point = 0; point < 2; ++point) {
      const __m256 x = _mm256_loadu_ps(soa + 2 * point * n + i);
      const __m256 y = _mm256_loadu_ps(soa + (2 * point + 1) * n + i);
      const __m256 row = round_away_avx2(_mm256_add_ps(_mm256_mul_ps(x, vsa), _mm256_mul_ps(y, vca)));
      const __m256 col = round_away_avx2(_mm256_sub_ps(_mm256_mul_ps(x, vca), _mm256_mul_ps(y, vsa)));
      // row * step + col: small integers, exact in float
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(offsets + point * n + i),
                          _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(row, vstep), col)));
    }
  }
  return i;
}
#endif

#if defined(RGBL_HAVE_AVX2_PATH)
// 8 tests per step: both sides gathered as 32-bit words (the sampled byte is the low one), compared,
// and the 8 signs are the descriptor's byte. Reads up to 3 bytes past each sampled pixel.
__attribute__((target("avx2"))) void brief_bits_avx2(const std::uint8_t* centre, const int* first, const int* second,
                                                     std::uint8_t* out32) {
  const __m256i low_byte = _mm256_set1_epi32(0xFF);
  const auto* base = reinterpret_cast<const int*>(centre);
  for (std::size_t byte = 0; byte < 32; ++byte) {
    const __m256i i1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(first + 8 * byte));
    const __m256i i2 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(second + 8 * byte));
    const __m256i a = _mm256_and_si256(_mm256_i32gather_epi32(base, i1, 1), low_byte);
    const __m256i b = _mm256_and_si256(_mm256_i32gather_epi32(base, i2, 1), low_byte);
    out32[byte] = static_cast<std::uint8_t>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(b, a))));
  }
}
#endif

}  // namespace

void rotate_pattern(std::span<const float> soa, float sa, float ca, int step, std::span<int> offsets,
                    bool allow_avx2) {
  const std::size_t n = soa.size() / 4;
  std::size_t i = 0;
#if defined(RGBL_HAVE_AVX2_PATH)
  if (allow_avx2 && cpu_has_avx2()) i = rotate_avx2(soa.data(), n, sa, ca, step, offsets.data());
#else
  (void)allow_avx2;
#endif
#if defined(__SSE2__)
  const __m128 vsa = _mm_set1_ps(sa), vca = _mm_set1_ps(ca);
  const __m128 vstep = _mm_set1_ps(static_cast<float>(step));
  for (; i + 4 <= n; i += 4) {
    for (std::size_t point = 0; point < 2; ++point) {
      const __m128 x = _mm_loadu_ps(soa.data() + 2 * point * n + i);
      const __m128 y = _mm_loadu_ps(soa.data() + (2 * point + 1) * n + i);
      const __m128 row = round_away_sse2(_mm_add_ps(_mm_mul_ps(x, vsa), _mm_mul_ps(y, vca)));
      const __m128 col = round_away_sse2(_mm_sub_ps(_mm_mul_ps(x, vca), _mm_mul_ps(y, vsa)));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(offsets.data() + point * n + i),
                       _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(row, vstep), col)));
    }
  }
#endif
  for (; i < n; ++i) {
    for (std::size_t point = 0; point < 2; ++point) {
      const float x = soa[2 * point * n + i], y = soa[(2 * point + 1) * n + i];
      offsets[point * n + i] = round_away(x * sa + y * ca) * step + round_away(x * ca - y * sa);
    }
  }
}

void brief_bits(const std::uint8_t* centre, std::span<const int> offsets, std::uint8_t* out32, bool allow_avx2) {
  const std::size_t n = offsets.size() / 2;
#if defined(RGBL_HAVE_AVX2_PATH)
  if (allow_avx2 && cpu_has_avx2()) {
    brief_bits_avx2(centre, offsets.data(), offsets.data() + n, out32);
    return;
  }
#else
  (void)allow_avx2;
#endif
#if defined(__SSE2__)
  // Gather both sides of every test, then compare 16 at a time: the byte mask's bits are the
  // descriptor's bits in order.
  alignas(16) std::array<std::uint8_t, 256> first{}, second{};
  for (std::size_t i = 0; i < 256; ++i) {
    first[i] = centre[offsets[i]];
    second[i] = centre[offsets[n + i]];
  }
  const __m128i flip = _mm_set1_epi8(static_cast<char>(0x80));  // unsigned order via the signed compare
  for (std::size_t i = 0; i < 256; i += 16) {
    const __m128i a = _mm_xor_si128(_mm_load_si128(reinterpret_cast<const __m128i*>(first.data() + i)), flip);
    const __m128i b = _mm_xor_si128(_mm_load_si128(reinterpret_cast<const __m128i*>(second.data() + i)), flip);
    const auto bits = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmplt_epi8(a, b)));
    out32[i / 8] = static_cast<std::uint8_t>(bits & 0xFFU);
    out32[i / 8 + 1] = static_cast<std::uint8_t>(bits >> 8U);
  }
#else
  for (std::size_t byte = 0; byte < 32; ++byte) {
    unsigned bits = 0;
    for (std::size_t bit = 0; bit < 8; ++bit) {
      const std::size_t i = byte * 8 + bit;
      bits |= static_cast<unsigned>(centre[offsets[i]] < centre[offsets[n + i]]) << bit;
    }
    out32[byte] = static_cast<std::uint8_t>(bits);
  }
#endif
}

}  // namespace rgbl::detail
