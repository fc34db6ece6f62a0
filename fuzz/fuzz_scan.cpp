// Any bytes as a velodyne .bin, read from a file as users do, then projected: either points or a
// ParseError, and projection never writes outside the image whatever the values (NaN, Inf, huge).
#include "rgbl/core/error.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/projection.hpp"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rgbl-fuzz-scan-" + std::to_string(::getpid()) + ".bin");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const auto points = rgbl::read_kitti_scan(path);
    rgbl::Matrix34d P;
    P << 700.0, 0.0, 600.0, 40.0, 0.0, 700.0, 180.0, 0.1, 0.0, 0.0, 1.0, 0.01;
    cv::Mat_<float> depth(37, 122);
    rgbl::ProjectionOptions options;
    options.min_depth = 0.0F;
    (void)rgbl::project_to_depth(points, P, options, depth);
  } catch (const rgbl::ParseError&) {
  }
  return 0;
}
