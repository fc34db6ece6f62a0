#pragma once
// Integer voxel coordinates and a flat hash from a voxel to an index. Checking a pose against a LiDAR
// scan (scan_agreement.hpp) looks up tens of thousands of voxels; an open-addressing table over two
// flat arrays does that without a node allocation per voxel.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace rgbl {

struct VoxelKey {
  std::int32_t x = 0, y = 0, z = 0;
  friend bool operator==(const VoxelKey&, const VoxelKey&) = default;
};

// The voxel of edge 1 / inv_size holding p.
inline VoxelKey voxel_of(const Eigen::Vector3f& p, float inv_size) {
  return {static_cast<std::int32_t>(std::floor(p.x() * inv_size)),
          static_cast<std::int32_t>(std::floor(p.y() * inv_size)),
          static_cast<std::int32_t>(std::floor(p.z() * inv_size))};
}
inline VoxelKey voxel_of(const Eigen::Vector3d& p, double inv_size) {
  return {static_cast<std::int32_t>(std::floor(p.x() * inv_size)),
          static_cast<std::int32_t>(std::floor(p.y() * inv_size)),
          static_cast<std::int32_t>(std::floor(p.z() * inv_size))};
}

// Voxel -> std::uint32_t. No erase: callers that drop voxels rebuild the index (clear + emplace).
// Coordinates are packed into 21 bits each, so voxels more than 2^20 apart alias (1048 km at 1 m).
class VoxelIndex {
 public:
  static constexpr std::uint32_t npos = std::numeric_limits<std::uint32_t>::max();

  std::size_t size() const { return size_; }

  void clear() {
    std::fill(slots_.begin(), slots_.end(), kEmpty);
    size_ = 0;
  }

  // Room for n voxels without growing.
  void reserve(std::size_t n) {
    std::size_t capacity = 16;
    while (capacity < 2 * n) capacity *= 2;
    if (capacity > slots_.size()) rehash(capacity);
  }

  std::uint32_t find(const VoxelKey& key) const {
    if (slots_.empty()) return npos;
    const std::uint64_t packed = pack(key);
    for (std::size_t i = slot_of(packed);; i = (i + 1) & mask_) {
      if (slots_[i] == packed) return values_[i];
      if (slots_[i] == kEmpty) return npos;
    }
  }

  // Stores key -> value unless the key is there; returns the stored value and whether it was new.
  std::pair<std::uint32_t, bool> emplace(const VoxelKey& key, std::uint32_t value) {
    if (2 * (size_ + 1) > slots_.size()) rehash(slots_.empty() ? 64 : 2 * slots_.size());
    const std::uint64_t packed = pack(key);
    for (std::size_t i = slot_of(packed);; i = (i + 1) & mask_) {
      if (slots_[i] == packed) return {values_[i], false};
      if (slots_[i] == kEmpty) {
        slots_[i] = packed;
        values_[i] = value;
        ++size_;
        return {value, true};
      }
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = 0;  // packed keys have bit 63 set, so 0 is never a key

  static std::uint64_t pack(const VoxelKey& k) {
    constexpr std::uint64_t m = (std::uint64_t{1} << 21) - 1;
    return (std::uint64_t{1} << 63) | ((static_cast<std::uint64_t>(k.x) & m) << 42) |
           ((static_cast<std::uint64_t>(k.y) & m) << 21) | (static_cast<std::uint64_t>(k.z) & m);
  }
  std::size_t slot_of(std::uint64_t packed) const {
    return static_cast<std::size_t>((packed * 0x9E3779B97F4A7C15ULL) >> shift_) & mask_;
  }
  void rehash(std::size_t capacity) {
    std::vector<std::uint64_t> old_slots(capacity, kEmpty);
    std::vector<std::uint32_t> old_values(capacity);
    old_slots.swap(slots_);
    old_values.swap(values_);
    mask_ = capacity - 1;
    shift_ = 64;
    for (std::size_t c = capacity; c > 1; c >>= 1) --shift_;
    for (std::size_t j = 0; j < old_slots.size(); ++j) {
      if (old_slots[j] == kEmpty) continue;
      std::size_t i = slot_of(old_slots[j]);
      while (slots_[i] != kEmpty) i = (i + 1) & mask_;
      slots_[i] = old_slots[j];
      values_[i] = old_values[j];
    }
  }

  std::vector<std::uint64_t> slots_;
  std::vector<std::uint32_t> values_;
  std::size_t size_ = 0;
  std::size_t mask_ = 0;
  int shift_ = 64;
};

// Points grouped by voxel of edge 1 / inv_size, for "which points are near p" queries: the points
// of the voxel at `slot = index.find(key)` are points[begin[slot] .. begin[slot + 1]), in their input
// order. Two passes (count per voxel, then place): no allocation per voxel.
struct VoxelBuckets {
  VoxelIndex index;
  std::vector<std::uint32_t> begin;
  std::vector<Eigen::Vector3f> points;

  VoxelBuckets() = default;
  VoxelBuckets(const std::vector<Eigen::Vector3f>& input, float inv_size) {
    std::vector<std::uint32_t> slot_of(input.size());
    std::vector<std::uint32_t> counts;
    index.reserve(input.size());
    for (std::size_t i = 0; i < input.size(); ++i) {
      const auto [slot, added] = index.emplace(voxel_of(input[i], inv_size), static_cast<std::uint32_t>(counts.size()));
      if (added) counts.push_back(0);
      ++counts[slot];
      slot_of[i] = slot;
    }
    begin.assign(counts.size() + 1, 0);
    for (std::size_t s = 0; s < counts.size(); ++s) begin[s + 1] = begin[s] + counts[s];
    std::vector<std::uint32_t> next(begin.begin(), begin.end() - 1);
    points.resize(input.size());
    for (std::size_t i = 0; i < input.size(); ++i) points[next[slot_of[i]]++] = input[i];
  }
};

}  // namespace rgbl
