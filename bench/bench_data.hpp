#pragma once
// Inputs for the microbenchmarks: the real KITTI seq 04 excerpt when present ($RGBL_DATA_DIR or
// ../shared/data), else a synthetic stand-in of the same size, announced on stderr.

#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <vector>

namespace rgbl::bench {

inline std::optional<std::filesystem::path> seq04() {
  const char* env = std::getenv("RGBL_DATA_DIR");
  const std::filesystem::path root = (env != nullptr && *env != '\0') ? env : RGBL_BENCH_DATA_DIR;
  const auto seq = root / "kitti/odometry/sequences/04";
  if (std::filesystem::exists(seq / "calib.txt")) return seq;
  return std::nullopt;
}

inline KittiCalibration calibration() {
  if (const auto seq = seq04()) return read_kitti_odometry_calibration(*seq / "calib.txt", 1226, 370);
  // sequence 04's calibration, for machines without the data
  KittiCalibration c;
  Matrix34d P;
  P << 707.0912, 0.0, 601.8873, 46.88783, 0.0, 707.0912, 183.1104, 0.1178601, 0.0, 0.0, 1.0, 6.203223e-3;
  c.P.fill(P);
  Matrix34d Tr;
  Tr << -1.857739e-03, -9.999660e-01, -8.039975e-03, -4.784030e-03, -6.481466e-03, 8.051860e-03, -9.999466e-01,
      -7.337429e-02, 9.999773e-01, -1.805529e-03, -6.496204e-03, -3.339968e-01;
  c.T_cam0_lidar = isometry_from_3x4(Tr);
  c.width.fill(1226);
  c.height.fill(370);
  return c;
}

// A real scan, or 120k points on a 64-beam pattern around the sensor.
inline std::vector<LidarPoint> scan(int frame = 0) {
  if (const auto seq = seq04()) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.bin", frame);
    return read_kitti_scan(*seq / "velodyne" / name);
  }
  std::fprintf(stderr, "rgbl_bench: no KITTI data found, using a synthetic 120k-point scan\n");
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> range(3.0F, 80.0F);
  std::vector<LidarPoint> points;
  points.reserve(120000);
  for (int beam = 0; beam < 64; ++beam) {
    const float elevation = (2.0F - 26.8F * static_cast<float>(beam) / 63.0F) * 3.14159265F / 180.0F;
    for (int i = 0; i < 1875; ++i) {
      const float azimuth = 2.0F * 3.14159265F * static_cast<float>(i) / 1875.0F;
      const float r = range(rng);
      points.push_back({r * std::cos(elevation) * std::cos(azimuth), r * std::cos(elevation) * std::sin(azimuth),
                        r * std::sin(elevation), 0.5F});
    }
  }
  return points;
}

// A real grey frame (image_0, 1226x370), or a synthetic textured image of the same size: smooth
// blobs plus random rectangles, so that FAST finds corners everywhere.
inline cv::Mat gray_image(int frame = 0) {
  if (const auto seq = seq04()) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", frame);
    cv::Mat img = cv::imread((*seq / "image_0" / name).string(), cv::IMREAD_GRAYSCALE);
    if (!img.empty()) return img;
  }
  std::fprintf(stderr, "rgbl_bench: no KITTI image found, using a synthetic textured 1226x370 image\n");
  std::mt19937 rng(7U + static_cast<unsigned>(frame));
  cv::Mat img(370, 1226, CV_8UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      img.at<std::uint8_t>(y, x) =
          static_cast<std::uint8_t>(128.0 + 60.0 * std::sin(x * 0.05) * std::cos(y * 0.07));
    }
  }
  std::uniform_int_distribution<int> px(0, img.cols - 1), py(0, img.rows - 1), side(3, 30), value(0, 255);
  for (int i = 0; i < 3000; ++i) {
    const cv::Rect r(px(rng), py(rng), side(rng), side(rng));
    img(r & cv::Rect(0, 0, img.cols, img.rows)).setTo(value(rng));
  }
  return img;
}

}  // namespace rgbl::bench
