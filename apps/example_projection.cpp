// rgbl_example_projection [<kitti-sequence-dir>]
// Projects LiDAR scans into camera 2 and prints how much of the image has depth and how long it took.
// Without an argument it builds a synthetic scan (flat road and a wall 30 m ahead, seen by a LiDAR
// mounted as on KITTI) so that it runs anywhere.
#include "rgbl/core/timer.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/projection.hpp"

#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <exception>
#include <filesystem>
#include <vector>

namespace {

rgbl::KittiCalibration embedded_calibration() {  // KITTI odometry sequence 04
  rgbl::KittiCalibration c;
  c.P[0] << 707.0912, 0.0, 601.8873, 0.0, 0.0, 707.0912, 183.1104, 0.0, 0.0, 0.0, 1.0, 0.0;
  c.P[1] << 707.0912, 0.0, 601.8873, -379.8145, 0.0, 707.0912, 183.1104, 0.0, 0.0, 0.0, 1.0, 0.0;
  c.P[2] << 707.0912, 0.0, 601.8873, 46.88783, 0.0, 707.0912, 183.1104, 0.1178601, 0.0, 0.0, 1.0, 6.203223e-3;
  c.P[3] << 707.0912, 0.0, 601.8873, -333.4597, 0.0, 707.0912, 183.1104, 1.930130, 0.0, 0.0, 1.0, 3.318498e-3;
  rgbl::Matrix34d Tr;
  Tr << -1.857739e-03, -9.999660e-01, -8.039975e-03, -4.784030e-03, -6.481466e-03, 8.051860e-03, -9.999466e-01,
      -7.337429e-02, 9.999773e-01, -1.805529e-03, -6.496204e-03, -3.339968e-01;
  c.T_cam0_lidar = rgbl::isometry_from_3x4(Tr);
  c.width.fill(1226);
  c.height.fill(370);
  return c;
}

// 64 beams from +2 deg to -24.8 deg, 0.2 deg azimuth steps; LiDAR 1.73 m above a flat road, a wall at x = 30 m.
std::vector<rgbl::LidarPoint> synthetic_scan() {
  std::vector<rgbl::LidarPoint> points;
  constexpr double kDeg = M_PI / 180.0;
  for (int beam = 0; beam < 64; ++beam) {
    const double elevation = (2.0 - 26.8 * beam / 63.0) * kDeg;
    for (int i = 0; i < 1800; ++i) {
      const double azimuth = i * 0.2 * kDeg;
      const Eigen::Vector3d dir(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                                std::sin(elevation));
      double range = 120.0;
      if (dir.z() < 0.0) range = std::min(range, 1.73 / -dir.z());
      if (dir.x() > 0.0) range = std::min(range, 30.0 / dir.x());
      const Eigen::Vector3d p = range * dir;
      points.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), 0.5F});
    }
  }
  return points;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const bool real = argc > 1;
    const std::filesystem::path seq = real ? argv[1] : "";
    const rgbl::KittiCalibration calib =
        real ? rgbl::read_kitti_odometry_calibration(seq / "calib.txt", 1226, 370) : embedded_calibration();
    const rgbl::CameraCalibration cam = calib.camera(2);
    const rgbl::ProjectionOptions options;
    options.validate();
    cv::Mat_<float> depth(cam.camera.height, cam.camera.width);
    std::vector<rgbl::LidarPoint> scan;
    const int frames = real ? 51 : 1;
    double total_ms = 0.0;
    long total_filled = 0;
    for (int frame = 0; frame < frames; ++frame) {
      if (real) {
        const auto file = seq / "velodyne" / fmt::format("{:06d}.bin", frame);
        if (!std::filesystem::exists(file)) break;
        rgbl::read_kitti_scan(file, scan);
      } else {
        scan = synthetic_scan();
      }
      rgbl::Stopwatch watch;
      total_filled += rgbl::project_to_depth(scan, cam.P_img_lidar(), options, depth);
      total_ms += watch.elapsed_ms();
      if (frame == 0) fmt::print("frame 0: {} points in the scan\n", scan.size());
    }
    const double pixels = static_cast<double>(depth.total()) * frames;
    fmt::print("{} scan(s) ({}) projected into camera 2 ({}x{}): {:.2f} % of pixels have depth, "
               "{:.3f} ms per scan\n",
               frames, real ? seq.string() : "synthetic", cam.camera.width, cam.camera.height,
               100.0 * static_cast<double>(total_filled) / pixels, total_ms / frames);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
