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

// Number of differing bits: popcount over four 64-bit words.
inline int hamming_distance(const Descriptor& a, const Descriptor& b) noexcept {
  int distance = 0;
  for (std::size_t i = 0; i < 32; i += 8) {
    std::uint64_t wa = 0, wb = 0;
    std::memcpy(&wa, a.data() + i, 8);
    std::memcpy(&wb, b.data() + i, 8);
    distance += std::popcount(wa ^ wb);
  }
  return distance;
}

}  // namespace rgbl
