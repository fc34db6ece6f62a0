// Any bytes as a KITTI odometry calib.txt and as a raw calib_cam_to_cam/velo_to_cam pair: the parsers
// must either return a calibration or throw rgbl::ParseError/ConfigError, never crash or hang.
#include "rgbl/core/error.hpp"
#include "rgbl/geometry/calibration.hpp"

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    std::istringstream in(text);
    const auto calib = rgbl::parse_kitti_odometry_calibration(in, "fuzz", 1226, 370);
    for (int i = 0; i < 4; ++i) (void)calib.camera(i).P_img_lidar();
  } catch (const rgbl::Error&) {
  }
  try {
    // split the input in two files at the first NUL-free midpoint
    const std::size_t half = text.size() / 2;
    std::istringstream cam(text.substr(0, half));
    std::istringstream velo(text.substr(half));
    const auto calib = rgbl::parse_kitti_raw_calibration(cam, "cam", velo, "velo");
    for (int i = 0; i < 4; ++i) (void)calib.camera(i).P_img_lidar();
  } catch (const rgbl::Error&) {
  }
  return 0;
}
