#pragma once
// The feature types every module above `features` speaks: keypoints and 256-bit binary descriptors.

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>

namespace rgbl {

struct Keypoint {
  float x = 0.0F, y = 0.0F;  // pixel position in the full-resolution image (integer = pixel centre)
  float angle = 0.0F;        // orientation, degrees in [0, 360)
  float response = 0.0F;     // detector score (higher is stronger)
  float size = 0.0F;         // patch diameter at level 0 scale, pixels
  int level = 0;             // pyramid level the keypoint was detected on
};

// 256-bit rotated-BRIEF descriptor.
using Descriptor = std::array<std::uint8_t, 32>;

// Bits set in a 64-bit word. Without -mpopcnt (rgbl never sets -march), std::popcount becomes a
// library call that dominated the tracker's profile; the branch-free SWAR count is a few instructions.
inline int popcount64(std::uint64_t x) noexcept {
#if defined(__POPCNT__)
  return std::popcount(x);
#else
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}

// Number of differing bits: popcount over four 64-bit words.
inline int hamming_distance(const Descriptor& a, const Descriptor& b) noexcept {
  int distance = 0;
  for (std::size_t i = 0; i < 32; i += 8) {
    std::uint64_t wa = 0, wb = 0;
    std::memcpy(&wa, a.data() + i, 8);
    std::memcpy(&wb, b.data() + i, 8);
    distance += popcount64(wa ^ wb);
  }
  return distance;
}

}  // namespace rgbl
