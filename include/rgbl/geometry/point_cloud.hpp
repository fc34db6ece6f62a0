#pragma once
// LiDAR scans. A KITTI velodyne .bin is a packed array of float32 (x, y, z, reflectance); LidarPoint
// has exactly that layout, so a scan already in memory can be viewed without copying.

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <iterator>
#include <span>
#include <type_traits>
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

// The most points read_kitti_scan reads from one file: 10 million (160 MB; a KITTI scan has ~120 000).
inline constexpr std::size_t kMaxScanPoints = 10'000'000;
// Seconds between a scan and its image beyond which the two are not one trigger's (KITTI: 17 ms
// apart): such a scan time is a glitch of the log, and the scan is taken as simultaneous.
inline constexpr double kMaxScanAge = 1.0;
// What a setting of that time must be (the settings key's and the options' message).
inline constexpr const char* kScanAgeExpected = "seconds from the scan to the image, -1 .. 1";

// Reads a KITTI .bin into `points` (reusing its capacity). Throws ParseError naming the file when it
// is not a readable regular file, its size is not a multiple of 16 bytes or it holds more than
// kMaxScanPoints points. Non-finite points are kept: the kernels
// skip them, and callers may want to count them.
void read_kitti_scan(const std::filesystem::path& path, std::vector<LidarPoint>& points);
std::vector<LidarPoint> read_kitti_scan(const std::filesystem::path& path);

// How rgbl reads a point type of yours. The primary template takes members x, y, z (any arithmetic
// type) and, when present, intensity; specialise it for a type with other names:
//   template <> struct rgbl::PointTraits<MyPoint> {
//     static Eigen::Vector3d position(const MyPoint& p) { return {p.pos[0], p.pos[1], p.pos[2]}; }
//     static float intensity(const MyPoint& p) { return p.reflectivity; }
//   };
template <typename Point>
struct PointTraits {
  static Eigen::Vector3d position(const Point& p) {
    return {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)};
  }
  static float intensity(const Point& p) {
    if constexpr (requires { p.intensity; }) {
      return static_cast<float>(p.intensity);
    } else {
      return 0.0F;
    }
  }
};

// Any range of points (PCL clouds, ROS messages converted, your own structs) as the LidarPoints the
// kernels take, reusing `out`'s capacity: one copy, so that the kernels stay compiled once, with their
// per-CPU clones.
template <typename Range>
void to_lidar_points(const Range& cloud, std::vector<LidarPoint>& out) {
  using Point = std::remove_cvref_t<decltype(*std::begin(cloud))>;
  out.clear();
  for (const auto& p : cloud) {
    const Eigen::Vector3d x = PointTraits<Point>::position(p);
    out.push_back({static_cast<float>(x.x()), static_cast<float>(x.y()), static_cast<float>(x.z()),
                   PointTraits<Point>::intensity(p)});
  }
}

}  // namespace rgbl
