// Any bytes as an ORB-SLAM style settings YAML, read from a file as users do (read_settings takes a
// path): either settings or rgbl::ParseError, never a crash, an abort inside OpenCV's FileStorage or
// a hang.
#include "rgbl/core/error.hpp"
#include "rgbl/io/settings.hpp"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rgbl-fuzz-settings-" + std::to_string(::getpid()) + ".yaml");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const auto settings = rgbl::read_settings(path);
    if (settings.camera) (void)settings.camera->K();
  } catch (const rgbl::ParseError&) {
  }
  return 0;
}
