// Any bytes as an image file, read as the loaders read frames (grey, colour, 16-bit depth): an image
// or rgbl::ParseError, never a crash, an escaping cv::Exception or gigabytes allocated for a header
// that claims a huge size.
#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"

#include <opencv2/imgcodecs.hpp>
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
  for (const int flags : {cv::IMREAD_GRAYSCALE, cv::IMREAD_COLOR, cv::IMREAD_ANYDEPTH}) {
    try {
      const cv::Mat image = rgbl::read_image_file(path, flags);
      if (image.empty()) std::abort();  // read_image_file never returns an empty image
    } catch (const rgbl::ParseError&) {
    }
  }
  return 0;
}
