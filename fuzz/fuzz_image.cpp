// Any bytes as an image file, read as the loaders read frames (grey, colour, 16-bit depth): an image
// or rgbl::ParseError, never a crash (the decoders' longjmp error paths), or gigabytes allocated for a header
// that claims a huge size.
#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rgbl-fuzz-image-" + std::to_string(::getpid()) + ".png");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  for (const rgbl::ImageMode mode : {rgbl::ImageMode::grey, rgbl::ImageMode::colour, rgbl::ImageMode::grey_any_depth}) {
    try {
      const cv::Mat image = rgbl::read_image_file(path, mode);
      if (image.empty()) std::abort();  // read_image_file never returns an empty image
    } catch (const rgbl::ParseError&) {
    }
  }
  return 0;
}
