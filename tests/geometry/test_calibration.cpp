#include "rgbl/core/error.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "support/data.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <sstream>
#include <string>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {
const char* kSeq04Calib =
    "P0: 7.070912e+02 0 6.018873e+02 0 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n"
    "P1: 7.070912e+02 0 6.018873e+02 -3.798145e+02 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n"
    "P2: 7.070912e+02 0 6.018873e+02 4.688783e+01 0 7.070912e+02 1.831104e+02 1.178601e-01 0 0 1 "
    "6.203223e-03\n"
    "P3: 7.070912e+02 0 6.018873e+02 -3.334597e+02 0 7.070912e+02 1.831104e+02 1.930130e+00 0 0 1 "
    "3.318498e-03\n"
    "Tr: -1.857739385241e-03 -9.999659513510e-01 -8.039975204516e-03 -4.784029760483e-03 "
    "-6.481465826011e-03 8.051860151134e-03 -9.999466081774e-01 -7.337429464231e-02 "
    "9.999773098287e-01 -1.805528627661e-03 -6.496203536139e-03 -3.339968064433e-01\n";

void check_seq04(const rgbl::KittiCalibration& calib) {
  // the grey stereo pair: 379.8145 / 707.0912 = 0.5371 m
  CHECK_THAT(calib.baseline(0, 1), WithinAbs(0.53716, 1e-4));
  // camera 2 sits ~6 cm from cam0 (SPEC: P2's 46.888 px), mostly along x
  const rgbl::CameraCalibration cam2 = calib.camera(2);
  const Eigen::Vector3d t = cam2.T_cam_cam0.translation();
  CHECK_THAT(t.x(), WithinAbs((46.88783 - 601.8873 * 6.203223e-3) / 707.0912, 1e-9));
  CHECK_THAT(t.z(), WithinAbs(6.203223e-3, 1e-12));
  CHECK_THAT(calib.baseline(0, 2), WithinAbs(0.0614, 5e-4));
  CHECK(cam2.camera.fx == 707.0912);
  CHECK(cam2.camera.width == 1226);
  // the LiDAR projection of camera 2 equals P2 * [Tr; 0 0 0 1] exactly
  Eigen::Matrix4d Tr = Eigen::Matrix4d::Identity();
  Tr.topRows<3>() = calib.T_cam0_lidar.matrix().topRows<3>();
  const rgbl::Matrix34d expected = calib.P[2] * Tr;
  CHECK((cam2.P_img_lidar() - expected).norm() < 1e-9);
}
}  // namespace

TEST_CASE("odometry calib.txt parses into cameras with their offsets") {
  rgbl::test::TempDir dir;
  const auto calib = rgbl::read_kitti_odometry_calibration(dir.write("calib.txt", kSeq04Calib), 1226, 370);
  check_seq04(calib);
}

TEST_CASE("real calib.txt of sequence 04") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  check_seq04(rgbl::read_kitti_odometry_calibration(*seq / "calib.txt", 1226, 370));
}

TEST_CASE("calibration errors name the file, the line and what was expected") {
  rgbl::test::TempDir dir;
  SECTION("missing file") {
    CHECK_THROWS_WITH(rgbl::read_kitti_odometry_calibration(dir.path() / "nope.txt"),
                      Contains("nope.txt") && Contains("missing"));
  }
  SECTION("missing key") {
    const auto file = dir.write("calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
    CHECK_THROWS_WITH(rgbl::read_kitti_odometry_calibration(file), Contains("'P1: ' followed by 12 numbers"));
  }
  SECTION("non-numeric value") {
    std::string text = kSeq04Calib;
    text.replace(text.find("4.688783e+01"), 12, "4.68x783e+01");
    const auto file = dir.write("calib.txt", text);
    CHECK_THROWS_WITH(rgbl::read_kitti_odometry_calibration(file),
                      Contains("calib.txt:3:") && Contains("expected 12 numbers after 'P2:'"));
  }
  SECTION("wrong count") {
    const auto file = dir.write("calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1\n");
    CHECK_THROWS_WITH(rgbl::read_kitti_odometry_calibration(file), Contains("calib.txt:1:") && Contains("found 11"));
  }
  SECTION("line without a colon") {
    const auto file = dir.write("calib.txt", "P0 1 0 0\n");
    CHECK_THROWS_AS(rgbl::read_kitti_odometry_calibration(file), rgbl::ParseError);
  }
  SECTION("not a projection") {
    std::string text = kSeq04Calib;
    text.replace(0, 14, "P0: 0.000e+00");
    const auto file = dir.write("calib.txt", text);
    CHECK_THROWS_WITH(rgbl::read_kitti_odometry_calibration(file), Contains("positive focal lengths"));
  }
}

TEST_CASE("calibration: implausible intrinsics, non-rigid Tr, duplicate keys refused, a byte order mark is skipped") {
  rgbl::test::TempDir dir;
  const auto error_of = [&](const std::string& text, int width = 0, int height = 0) -> std::string {
    const auto file = dir.write("calib.txt", text);
    try {
      (void)rgbl::read_kitti_odometry_calibration(file, width, height);
    } catch (const rgbl::ParseError& e) {
      CHECK(e.file() == file);
      return e.what();
    }
    return "no error";
  };
  const auto with_p0_focal = [](const std::string& f) {
    std::string text = kSeq04Calib;
    text.replace(text.find("7.070912e+02"), 12, f);
    text.replace(text.find("7.070912e+02"), 12, f);  // fy: the second of the line
    return text;
  };
  // these gave a trajectory of -nan rows and "ATE RMSE -nan m"
  CHECK_THAT(error_of(with_p0_focal("1e-300")), Contains("calib.txt:1: 'P0': focal lengths fx 1e-300 fy 1e-300 px"));
  CHECK_THAT(error_of(with_p0_focal("1e155")), Contains("calib.txt:1: 'P0': focal lengths"));
  // relative to the image, when its size is known
  CHECK_THAT(error_of(with_p0_focal("5"), 1226, 370), Contains("implausible for a 1226x370 image"));
  CHECK(error_of(with_p0_focal("5")) == "no error");  // no size yet: the loader checks once it has one
  std::string text = kSeq04Calib;
  text.replace(text.find("6.018873e+02"), 12, "6.018873e+05");
  CHECK_THAT(error_of(text, 1226, 370), Contains("principal point"));
  // Tr all zeros, or its rotation scaled by 2
  const std::string tr_zero = std::string(kSeq04Calib).substr(0, std::string(kSeq04Calib).find("Tr:")) +
                              "Tr: 0 0 0 0 0 0 0 0 0 0 0 0\n";
  CHECK_THAT(error_of(tr_zero), Contains("calib.txt:5: expected 'Tr' to hold a rotation matrix"));
  const std::string tr_scaled = std::string(kSeq04Calib).substr(0, std::string(kSeq04Calib).find("Tr:")) +
                                "Tr: 0 -2 0 0 0 0 -2 -0.08 2 0 0 -0.27\n";
  CHECK_THAT(error_of(tr_scaled), Contains("calib.txt:5: expected 'Tr' to hold a rotation matrix"));
  const std::string tr_far = std::string(kSeq04Calib).substr(0, std::string(kSeq04Calib).find("Tr:")) +
                             "Tr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 1e300\n";
  CHECK_THAT(error_of(tr_far), Contains("calib.txt:5: expected 'Tr' to hold a translation"));
  // a second P0 used to replace the first silently
  CHECK_THAT(error_of(std::string(kSeq04Calib) + "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n"),
             Contains("calib.txt:6: 'P0' given twice (lines 1 and 6)"));
  // a UTF-8 byte order mark (Windows editors) used to hide the first key
  CHECK(error_of("\xEF\xBB\xBF" + std::string(kSeq04Calib)) == "no error");
}

TEST_CASE("raw calibration: velo_to_cam R must be a rotation, R_rect_00 too") {
  rgbl::test::TempDir dir;
  std::string cam;
  for (int i = 0; i < 4; ++i) {
    cam += fmt::format("S_rect_0{}: 1.242000e+03 3.750000e+02\n", i);
    cam += fmt::format("P_rect_0{}: 7.215377e+02 0 6.095593e+02 0 0 7.215377e+02 1.728540e+02 0 0 0 1 0\n", i);
  }
  const std::string rect = "R_rect_00: 1 0 0 0 1 0 0 0 1\n";
  const std::string velo = "calib_time: 15-Mar-2012 11:37:16\nR: 0 -1 0 0 0 -1 1 0 0\nT: 0 -0.08 -0.27\n";
  const auto parse = [&](const std::string& c, const std::string& v) -> std::string {
    std::istringstream cam_in(c), velo_in(v);
    try {
      (void)rgbl::parse_kitti_raw_calibration(cam_in, "calib_cam_to_cam.txt", velo_in, "calib_velo_to_cam.txt");
    } catch (const rgbl::ParseError& e) {
      return e.what();
    }
    return "no error";
  };
  CHECK(parse(cam + rect, velo) == "no error");
  CHECK_THAT(parse(cam + rect, "R: 0 -2 0 0 0 -2 2 0 0\nT: 0 -0.08 -0.27\n"),
             Contains("calib_velo_to_cam.txt:1: expected 'R' to hold a rotation matrix"));
  CHECK_THAT(parse(cam + "R_rect_00: 0 0 0 0 0 0 0 0 0\n", velo),
             Contains("calib_cam_to_cam.txt:9: expected 'R_rect_00' to hold a rotation matrix"));
}

TEST_CASE("raw calibration chains velodyne -> cam0 -> rectified -> camera i") {
  const auto raw = rgbl::test::find_data("kitti/raw/2011_09_26");
  if (!raw) return;
  const auto calib = rgbl::read_kitti_raw_calibration(*raw);
  CHECK(calib.width[2] == 1242);
  CHECK(calib.height[2] == 375);
  // independent chain from the file values: P_rect_02 * R_rect_00 * [R | T]
  Eigen::Matrix<double, 3, 4> P2;
  P2 << 7.215377e+02, 0.0, 6.095593e+02, 4.485728e+01, 0.0, 7.215377e+02, 1.728540e+02, 2.163791e-01, 0.0,
      0.0, 1.0, 2.745884e-03;
  Eigen::Matrix4d R_rect = Eigen::Matrix4d::Identity();
  R_rect.topLeftCorner<3, 3>() << 9.999239e-01, 9.837760e-03, -7.445048e-03, -9.869795e-03, 9.999421e-01,
      -4.278459e-03, 7.402527e-03, 4.351614e-03, 9.999631e-01;
  Eigen::Matrix4d T_velo = Eigen::Matrix4d::Identity();
  T_velo.topRows<3>() << 7.533745e-03, -9.999714e-01, -6.166020e-04, -4.069766e-03, 1.480249e-02,
      7.280733e-04, -9.998902e-01, -7.631618e-02, 9.998621e-01, 7.523790e-03, 1.480755e-02, -2.717806e-01;
  const Eigen::Matrix<double, 3, 4> expected = P2 * R_rect * T_velo;
  CHECK((calib.camera(2).P_img_lidar() - expected).norm() < 1e-9);
  CHECK_THAT(calib.baseline(0, 1), WithinAbs(3.875744e+02 / 7.215377e+02, 1e-9));
}

TEST_CASE("camera index outside 0..3 is a config error") {
  rgbl::KittiCalibration calib;
  CHECK_THROWS_AS(calib.camera(4), rgbl::ConfigError);
}
