#pragma once
// LiDAR scans. A KITTI velodyne .bin is a packed array of float32 (x, y, z, reflectance); LidarPoint
// has exactly that layout, so a scan already in memory can be viewed without copying.

#include <cstddef>
#include <filesystem>
#include <span>
#include <vector>

namespace rgbl {

struct LidarPoint {
  float x = 0.0F, y = 0.0F, z = 0.0F;
  float intensity = 0.0F;
};
static_assert(sizeof(LidarPoint) == 4 * sizeof(float), "LidarPoint must match the KITTI .bin layout");

// Non-owning view of a scan: what every kernel takes.
using PointCloudView = std::span<const LidarPoint>;

// Views a packed float buffer of (x, y, z, reflectance) quadruples as points, without copying.
// Returns an empty view when the size is not a multiple of 4.
PointCloudView view_kitti_scan(std::span<const float> packed);

// Reads a KITTI .bin into `points` (reusing its capacity). Throws ParseError naming the file when it
// cannot be read or its size is not a multiple of 16 bytes. Non-finite points are kept: the kernels
// skip them, and callers may want to count them.
void read_kitti_scan(const std::filesystem::path& path, std::vector<LidarPoint>& points);
std::vector<LidarPoint> read_kitti_scan(const std::filesystem::path& path);

}  // namespace rgbl
