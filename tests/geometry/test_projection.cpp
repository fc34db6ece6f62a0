#include "rgbl/core/error.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/projection.hpp"
#include "support/data.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>

#include <array>
#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <limits>
#include <sys/stat.h>

using Catch::Matchers::Contains;

namespace {

// LiDAR frame == camera frame, f = 100 px, 64x48 image, principal point (32, 24).
rgbl::Matrix34d simple_projection() {
  rgbl::Matrix34d P;
  P << 100.0, 0.0, 32.0, 0.0, 0.0, 100.0, 24.0, 0.0, 0.0, 0.0, 1.0, 0.0;
  return P;
}

// Straightforward double-precision z-buffer, for comparison.
cv::Mat_<float> brute_force(rgbl::PointCloudView cloud, const rgbl::Matrix34d& P, int w, int h,
                            const rgbl::ProjectionOptions& o) {
  cv::Mat_<float> depth(h, w, 0.0F);
  for (const auto& p : cloud) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3d x = P * Eigen::Vector4d(p.x, p.y, p.z, 1.0);
    if (x.z() <= o.min_depth || x.z() >= o.max_depth) continue;
    const long u = std::lround(x.x() / x.z()), v = std::lround(x.y() / x.z());
    if (u < 0 || v < 0 || u >= w || v >= h) continue;
    float& cell = depth(static_cast<int>(v), static_cast<int>(u));
    if (cell == 0.0F || x.z() < cell) cell = static_cast<float>(x.z());
  }
  return depth;
}

}  // namespace

TEST_CASE("projection lands on the nearest pixel centre with camera z as depth") {
  const std::vector<rgbl::LidarPoint> cloud = {{0.0F, 0.0F, 10.0F, 0.0F},     // centre (32, 24)
                                               {1.0F, 0.5F, 10.0F, 0.0F},     // (42, 29)
                                               {-1.54F, -0.24F, 10.0F, 0.0F}};  // (16.6, 21.6) -> (17, 22)
  rgbl::ProjectionOptions options;
  options.min_depth = 1.0F;
  const cv::Mat_<float> depth = rgbl::project_to_depth(cloud, simple_projection(), 64, 48, options);
  CHECK(depth(24, 32) == 10.0F);
  CHECK(depth(29, 42) == 10.0F);
  CHECK(depth(22, 17) == 10.0F);
  CHECK(cv::countNonZero(depth) == 3);
}

TEST_CASE("z-buffer: the nearest point wins whatever the scan order") {
  rgbl::ProjectionOptions options;
  options.min_depth = 1.0F;
  // both hit pixel (32, 24); the nearer one comes first in scan order, then a farther one
  const std::vector<rgbl::LidarPoint> near_first = {{0.0F, 0.0F, 8.0F, 0.0F}, {0.0F, 0.0F, 30.0F, 0.0F}};
  const std::vector<rgbl::LidarPoint> far_first = {{0.0F, 0.0F, 30.0F, 0.0F}, {0.0F, 0.0F, 8.0F, 0.0F}};
  CHECK(rgbl::project_to_depth(near_first, simple_projection(), 64, 48, options)(24, 32) == 8.0F);
  CHECK(rgbl::project_to_depth(far_first, simple_projection(), 64, 48, options)(24, 32) == 8.0F);
}

TEST_CASE("range filter keeps min < z < max only") {
  rgbl::ProjectionOptions options;
  options.min_depth = 5.0F;
  options.max_depth = 50.0F;
  const std::vector<rgbl::LidarPoint> cloud = {{0.0F, 0.0F, 5.0F, 0.0F},   {0.0F, 0.0F, -10.0F, 0.0F},
                                               {0.0F, 0.0F, 50.0F, 0.0F},  {0.0F, 0.0F, 80.0F, 0.0F},
                                               {0.1F, 0.0F, 5.01F, 0.0F}, {0.0F, 1.0F, 49.9F, 0.0F}};
  cv::Mat_<float> depth(48, 64);
  const int filled = rgbl::project_to_depth(cloud, simple_projection(), options, depth);
  CHECK(filled == 2);
  CHECK(cv::countNonZero(depth) == 2);
  CHECK(depth(24, 34) == 5.01F);  // u = 32 + 100 * 0.1 / 5.01
  CHECK(depth(26, 32) == 49.9F);  // v = 24 + 100 * 1.0 / 49.9
  CHECK(depth(24, 32) == 0.0F);
}

TEST_CASE("non-finite points are skipped") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<rgbl::LidarPoint> cloud = {
      {nan, 0.0F, 10.0F, 0.0F}, {0.0F, inf, 10.0F, 0.0F}, {0.0F, 0.0F, inf, 0.0F}, {0.0F, 0.0F, nan, 0.0F},
      {-inf, 0.0F, 10.0F, 0.0F}, {0.0F, 0.0F, 10.0F, 0.0F}};
  rgbl::ProjectionOptions options;
  options.min_depth = 1.0F;
  const cv::Mat_<float> depth = rgbl::project_to_depth(cloud, simple_projection(), 64, 48, options);
  CHECK(cv::countNonZero(depth) == 1);
  CHECK(depth(24, 32) == 10.0F);
}

TEST_CASE("projection options validate") {
  rgbl::ProjectionOptions options;
  CHECK_NOTHROW(options.validate());
  options.max_depth = 2.0F;
  CHECK_THROWS_WITH(options.validate(), Contains("projection.max_depth"));
}

TEST_CASE("scan reader checks the record size") {
  rgbl::test::TempDir dir;
  const auto bad = dir.write("bad.bin", std::string(17, '\0'));
  CHECK_THROWS_WITH(rgbl::read_kitti_scan(bad), Contains("bad.bin") && Contains("not a multiple of 16"));
  CHECK_THROWS_WITH(rgbl::read_kitti_scan(dir.path() / "missing.bin"), Contains("missing.bin"));
  const auto empty = dir.write("empty.bin", "");
  CHECK(rgbl::read_kitti_scan(empty).empty());
  const float raw[8] = {1.0F, 2.0F, 3.0F, 0.5F, 4.0F, 5.0F, 6.0F, 0.25F};
  const auto good = dir.write("good.bin", std::string(reinterpret_cast<const char*>(raw), sizeof(raw)));
  const auto points = rgbl::read_kitti_scan(good);
  REQUIRE(points.size() == 2);
  CHECK(points[1].y == 5.0F);
  CHECK(points[1].intensity == 0.25F);
  // and the same buffer viewed in place, without a copy
  const rgbl::PointCloudView view = rgbl::view_kitti_scan(raw);
  REQUIRE(view.size() == 2);
  CHECK(static_cast<const void*>(view.data()) == static_cast<const void*>(raw));
  CHECK(view[0].z == 3.0F);
  CHECK(rgbl::view_kitti_scan(std::span<const float>(raw, 7)).empty());
}

TEST_CASE("scan reader refuses folders, FIFOs and scans beyond kMaxScanPoints, naming the file") {
  rgbl::test::TempDir dir;
  // a folder used to report its size as 9223372036854775807 bytes
  std::filesystem::create_directories(dir.path() / "folder.bin");
  CHECK_THROWS_WITH(rgbl::read_kitti_scan(dir.path() / "folder.bin"), Contains("folder.bin: is a directory"));
  const auto fifo = dir.path() / "fifo.bin";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THROWS_WITH(rgbl::read_kitti_scan(fifo), Contains("fifo.bin: is not a regular file"));
  // one point too many (a sparse file: nothing is written), refused before allocating
  const auto huge = dir.write("huge.bin", "");
  std::filesystem::resize_file(huge, (rgbl::kMaxScanPoints + 1) * 16);
  CHECK_THROWS_WITH(rgbl::read_kitti_scan(huge), Contains("huge.bin: holds 10000001 points, more than rgbl reads"));
}

TEST_CASE("real KITTI seq 04: all 51 scans into camera 2") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  const auto calib = rgbl::read_kitti_odometry_calibration(*seq / "calib.txt", 1226, 370);
  const rgbl::CameraCalibration cam2 = calib.camera(2);
  const rgbl::Matrix34d P = cam2.P_img_lidar();
  const rgbl::ProjectionOptions options;  // the paper's 5 m .. 200 m
  cv::Mat_<float> depth(370, 1226);
  std::vector<rgbl::LidarPoint> scan;
  double fill_sum = 0.0;
  for (int frame = 0; frame <= 50; ++frame) {
    rgbl::read_kitti_scan(*seq / "velodyne" / fmt::format("{:06d}.bin", frame), scan);
    REQUIRE(scan.size() > 100000);
    const int filled = rgbl::project_to_depth(scan, P, options, depth);
    const double fill = static_cast<double>(filled) / (1226.0 * 370.0);
    fill_sum += fill;
    INFO("frame " << frame << ": " << filled << " pixels filled");
    CHECK(filled == cv::countNonZero(depth));
    CHECK(filled > 14000);
    CHECK(filled < 24000);
    // nearest won: identical to a double-precision z-buffer except where float and double round a
    // pixel coordinate sitting within ~1e-5 px of .5 differently (each such point moves 2 pixels)
    const cv::Mat_<float> expected = brute_force(scan, P, 1226, 370, options);
    cv::Mat diff;
    cv::absdiff(depth, expected, diff);
    CHECK(cv::countNonZero(diff > 1e-4) <= 20);
  }
  const double mean_fill = fill_sum / 51.0;
  INFO("mean fill " << mean_fill);
  CHECK(mean_fill > 0.03);
  CHECK(mean_fill < 0.05);
}

namespace {

struct DoublePoint {  // x, y, z of another type, no intensity
  double x, y, z;
};

struct OtherNames {  // a type the primary traits cannot read
  std::array<float, 3> pos;
  float reflectivity;
};

}  // namespace

template <>
struct rgbl::PointTraits<OtherNames> {
  static Eigen::Vector3d position(const OtherNames& p) { return {p.pos[0], p.pos[1], p.pos[2]}; }
  static float intensity(const OtherNames& p) { return p.reflectivity; }
};

TEST_CASE("foreign point types reach the kernels through PointTraits") {
  const std::vector<DoublePoint> doubles = {{0.0, 0.0, 10.0}, {1.0, -0.4, 20.0}};
  std::vector<rgbl::LidarPoint> points(7);  // reused, not appended to
  rgbl::to_lidar_points(doubles, points);
  REQUIRE(points.size() == 2);
  CHECK(points[1].x == 1.0F);
  CHECK(points[1].y == -0.4F);
  CHECK(points[1].z == 20.0F);
  CHECK(points[1].intensity == 0.0F);
  const OtherNames other[] = {{{0.0F, 0.0F, 10.0F}, 0.7F}, {{1.0F, -0.4F, 20.0F}, 0.2F}};
  std::vector<rgbl::LidarPoint> converted;
  rgbl::to_lidar_points(other, converted);
  REQUIRE(converted.size() == 2);
  CHECK(converted[0].intensity == 0.7F);
  CHECK(converted[1].z == 20.0F);
  rgbl::Matrix34d P;
  P << 100.0, 0.0, 32.0, 0.0, 0.0, 100.0, 24.0, 0.0, 0.0, 0.0, 1.0, 0.0;
  const cv::Mat_<float> a = rgbl::project_to_depth(points, P, 64, 48, {1.0F, 100.0F});
  const cv::Mat_<float> b = rgbl::project_to_depth(converted, P, 64, 48, {1.0F, 100.0F});
  CHECK(a(24, 32) == 10.0F);
  CHECK(a(22, 37) == 20.0F);  // (1, -0.4, 20): u = 32 + 100 / 20, v = 24 - 40 / 20
  CHECK(cv::countNonZero(a != b) == 0);
}
