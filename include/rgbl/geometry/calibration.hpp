#pragma once
// KITTI calibration files parsed into typed cameras and extrinsics.
//
// Odometry `calib.txt`: P0..P3 are the rectified cameras' 3x4 projections, all with the same
// rotation as cam0 and P_i = K_i [I | t_i]; Tr maps velodyne points into rectified cam0.
// Raw `calib_cam_to_cam.txt` + `calib_velo_to_cam.txt`: velodyne -> unrectified cam0 (R, T), then
// R_rect_00 into rectified cam0, then P_rect_0i as above.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/se3.hpp"

#include <array>
#include <filesystem>
#include <iosfwd>

namespace rgbl {

// Everything needed to use one rectified camera of a rig with a LiDAR.
struct CameraCalibration {
  PinholeCamera camera;
  Eigen::Isometry3d T_cam_cam0 = Eigen::Isometry3d::Identity();   // rig reference: rectified cam0
  Eigen::Isometry3d T_cam_lidar = Eigen::Isometry3d::Identity();

  // 3x4 matrix taking homogeneous LiDAR points to homogeneous pixels: K * [R | t] of T_cam_lidar.
  // Its third row gives the camera depth z.
  Matrix34d P_img_lidar() const;
};

struct KittiCalibration {
  std::array<Matrix34d, 4> P{};                                     // rectified projections P0..P3
  Eigen::Isometry3d T_cam0_lidar = Eigen::Isometry3d::Identity();  // KITTI's Tr
  std::array<int, 4> width{}, height{};                             // image size per camera

  // Camera i (0..3) with its offset from cam0 (the 4th column of P_i, which need not be zero).
  CameraCalibration camera(int index) const;
  // Distance between the optical centres of two cameras, metres.
  double baseline(int a, int b) const;
};

// Reads an odometry calib.txt. The file carries no image size: pass it (KITTI: 1241x376 for
// sequences 00-02, 1242x375 for 03, 1226x370 for 04-12) or leave 0 to fill it in later.
// Throws ParseError naming the file, line and the expected content.
KittiCalibration read_kitti_odometry_calibration(const std::filesystem::path& calib_txt, int width = 0,
                                                 int height = 0);

// Reads a raw drive's calibration from the date folder holding calib_cam_to_cam.txt and
// calib_velo_to_cam.txt. Image sizes come from S_rect_0i.
KittiCalibration read_kitti_raw_calibration(const std::filesystem::path& date_dir);

// The same parsers over streams; `source` names the input in error messages.
KittiCalibration parse_kitti_odometry_calibration(std::istream& in, const std::filesystem::path& source,
                                                  int width = 0, int height = 0);
KittiCalibration parse_kitti_raw_calibration(std::istream& cam_to_cam, const std::filesystem::path& cam_source,
                                             std::istream& velo_to_cam, const std::filesystem::path& velo_source);

}  // namespace rgbl
