#pragma once
// Internal: the two inner loops of a BRIEF descriptor, vectorised. Both give exactly what the plain
// definitions (written out in the comments) give, on every path.

#include <cstddef>
#include <cstdint>
#include <span>

namespace rgbl::detail {

// The pattern's points rotated by the keypoint's angle into offsets from its pixel in an image with
// row stride `step`. `soa` holds the n pairs as x1[n], y1[n], x2[n], y2[n]; `offsets` receives the n
// first points, then the n second points:
//   offset = round(x sa + y ca) * step + round(x ca - y sa), rounding half away from zero,
// with the float operations in that order (no FMA contraction on the default x86-64 target, and the
// AVX2 path does not enable FMA). `allow_avx2 = false` forces SSE2 (or scalar), for tests.
void rotate_pattern(std::span<const float> soa, float sa, float ca, int step, std::span<int> offsets,
                    bool allow_avx2 = true);

// The 256 tests of a descriptor around `centre`: bit i (bit i % 8 of byte i / 8) is set where
// centre[offsets[i]] < centre[offsets[n + i]], n = offsets.size() / 2 >= 256. The AVX2 path reads
// whole 32-bit words, so 3 bytes after every sampled pixel must be readable (the extractor's
// keypoints keep edge_threshold > patch_size / 2 from the borders, so they lie in the image).
void brief_bits(const std::uint8_t* centre, std::span<const int> offsets, std::uint8_t* out32,
                bool allow_avx2 = true);

}  // namespace rgbl::detail
