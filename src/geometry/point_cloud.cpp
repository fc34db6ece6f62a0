#include "rgbl/geometry/point_cloud.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>

#include <fstream>

namespace rgbl {

PointCloudView view_kitti_scan(std::span<const float> packed) {
  if (packed.size() % 4 != 0) return {};
  // LidarPoint is a standard-layout aggregate of four floats with no padding (static_assert above).
  return {reinterpret_cast<const LidarPoint*>(packed.data()), packed.size() / 4};  // NOLINT
}

void read_kitti_scan(const std::filesystem::path& path, std::vector<LidarPoint>& points) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw ParseError(path, 0, "cannot open the file (expected a KITTI velodyne .bin scan)");
  const auto bytes = static_cast<std::size_t>(in.tellg());
  if (bytes % sizeof(LidarPoint) != 0) {
    throw ParseError(path, 0,
                     fmt::format("size {} bytes is not a multiple of 16 (expected float32 x, y, z, "
                                 "reflectance records; truncated download?)",
                                 bytes));
  }
  points.resize(bytes / sizeof(LidarPoint));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(points.data()), static_cast<std::streamsize>(bytes))) {  // NOLINT
    throw ParseError(path, 0, fmt::format("could not read {} bytes", bytes));
  }
}

std::vector<LidarPoint> read_kitti_scan(const std::filesystem::path& path) {
  std::vector<LidarPoint> points;
  read_kitti_scan(path, points);
  return points;
}

}  // namespace rgbl
