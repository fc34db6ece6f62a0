// Any bytes as a trajectory file in both formats (KITTI rows of 12 numbers, TUM `t tx ty tz qx qy qz
// qw`), read from a file as `rgbl eval` does: poses or rgbl::ParseError, never a crash or a hang.
#include "rgbl/core/error.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = std::filesystem::temp_directory_path();
  static const std::string pid = std::to_string(::getpid());
  static const std::filesystem::path path = dir / ("rgbl-fuzz-trajectory-" + pid + ".txt");
  static const std::filesystem::path copy = dir / ("rgbl-fuzz-trajectory-" + pid + "-out.txt");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  // A file that parses must write back and read again unchanged in size: a ParseError there escapes
  // and libFuzzer reports it.
  std::optional<std::vector<Eigen::Isometry3d>> poses;
  try {
    poses = rgbl::read_kitti_trajectory(path);
  } catch (const rgbl::ParseError&) {
  }
  if (poses) {
    rgbl::write_kitti_trajectory(copy, *poses);
    if (rgbl::read_kitti_trajectory(copy).size() != poses->size()) std::abort();
  }
  std::optional<rgbl::Trajectory> trajectory;
  try {
    trajectory = rgbl::read_tum_trajectory(path);
  } catch (const rgbl::ParseError&) {
  }
  if (trajectory) {
    if (trajectory->timestamps.size() != trajectory->poses.size()) std::abort();
    rgbl::write_tum_trajectory(copy, *trajectory);
    if (rgbl::read_tum_trajectory(copy).size() != trajectory->size()) std::abort();
  }
  return 0;
}
