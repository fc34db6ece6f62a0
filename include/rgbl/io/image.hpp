#pragma once
// Reading one image file, as every dataset loader does.

#include <opencv2/core/mat.hpp>

#include <filesystem>

namespace rgbl {

// Decodes `file` with cv::imread's `flags` (cv::IMREAD_GRAYSCALE, IMREAD_COLOR, IMREAD_ANYDEPTH). The
// file must be a readable regular file and, for a PNG, at most kMaxImagePixels large (checked on its
// header before decoding; see rgbl/core/file.hpp). Throws ParseError naming the file otherwise or when
// it cannot be decoded; never returns an empty image.
cv::Mat read_image_file(const std::filesystem::path& file, int flags);

}  // namespace rgbl
