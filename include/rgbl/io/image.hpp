#pragma once
// Reading one image file, as every dataset loader does, and writing one as every writer does.

#include <opencv2/core/mat.hpp>

#include <filesystem>

namespace rgbl {

// Decodes `file` with cv::imread's `flags` (cv::IMREAD_GRAYSCALE, IMREAD_COLOR, IMREAD_ANYDEPTH). The
// file must be a readable regular file and, for a PNG, at most kMaxImagePixels large (checked on its
// header before decoding; see rgbl/core/file.hpp). Throws ParseError naming the file otherwise or when
// it cannot be decoded; never returns an empty image.
cv::Mat read_image_file(const std::filesystem::path& file, int flags);

// Encodes `image` as PNG and writes it through write_atomically (rgbl/core/file.hpp): a reader never
// sees half a file, an interrupted writer leaves none. Throws Error naming the file.
void write_png_file(const std::filesystem::path& file, const cv::Mat& image);

// Depth in metres as the 16-bit PNG value of KITTI depth completion: round(depth * 256). 0 means no
// depth, and is also what a depth that does not fit gets (above 255.996 m, <= 0, NaN): a saturated
// 65535 would read back as a false 256 m.
cv::Mat encode_depth16(const cv::Mat_<float>& depth);

}  // namespace rgbl
