#include "rgbl/geometry/point_cloud.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <fmt/format.h>

#include <fstream>
#include <string_view>
#include <system_error>

namespace rgbl {

PointCloudView view_kitti_scan(std::span<const float> packed) {
  if (packed.size() % 4 != 0) return {};
  // LidarPoint is a standard-layout aggregate of four floats with no padding (static_assert above).
  return {reinterpret_cast<const LidarPoint*>(packed.data()), packed.size() / 4};  // NOLINT
}

void read_kitti_scan(const std::filesystem::path& path, std::vector<LidarPoint>& points) {
  constexpr std::string_view kWhat = "a KITTI velodyne .bin scan";
  std::ifstream in = open_input_file(path, kWhat, true);
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) throw ParseError(path, 0, fmt::format("cannot tell its size: {} (expected {})", ec.message(), kWhat));
  if (bytes % sizeof(LidarPoint) != 0) {
    throw ParseError(path, 0,
                     fmt::format("size {} bytes is not a multiple of 16 (expected float32 x, y, z, "
                                 "reflectance records; truncated download?)",
                                 bytes));
  }
  if (bytes / sizeof(LidarPoint) > kMaxScanPoints) {
    throw ParseError(path, 0,
                     fmt::format("holds {} points, more than rgbl reads ({}; a KITTI scan has about 120000)",
                                 bytes / sizeof(LidarPoint), kMaxScanPoints));
  }
  points.resize(bytes / sizeof(LidarPoint));
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
