// Any bytes as a KITTI odometry times.txt and as a raw timestamps.txt, read from a file as the loaders
// do: finite, strictly increasing times or rgbl::ParseError, never a crash or a hang.
#include "rgbl/core/error.hpp"
#include "rgbl/io/kitti_raw.hpp"
#include "rgbl/io/sequence.hpp"

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

void check_increasing(const std::vector<double>& times) {
  for (std::size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i]) || (i > 0 && !(times[i] > times[i - 1]))) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rgbl-fuzz-timestamps-" + std::to_string(::getpid()) + ".txt");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    check_increasing(rgbl::read_kitti_times(path));
  } catch (const rgbl::ParseError&) {
  }
  try {
    check_increasing(rgbl::read_kitti_raw_timestamps(path));
  } catch (const rgbl::ParseError&) {
  }
  return 0;
}
