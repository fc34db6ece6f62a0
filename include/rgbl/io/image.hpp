#pragma once
// Reading one image file, as every dataset loader does, and writing one as every writer does.

#include <opencv2/core/mat.hpp>

#include <filesystem>
#include <string_view>
#include <vector>

namespace rgbl {

// What read_image_file returns, as cv::imread's flags would: 8-bit grey (IMREAD_GRAYSCALE), 8-bit BGR
// (IMREAD_COLOR), or grey at the file's own depth, 16 bits for a 16-bit file (IMREAD_ANYDEPTH).
enum class ImageMode { grey, colour, grey_any_depth };

// Decodes a PNG or JPEG `file` to the pixels cv::imread gives for the same mode (libpng and libjpeg
// set up as OpenCV 4.6 does; a JPEG's EXIF orientation is not applied, where cv::imread turns the
// image by it), without OpenCV's imgcodecs. The file must be a readable regular file
// and at most kMaxImagePixels large (checked on its header before decoding; see rgbl/core/file.hpp).
// Throws ParseError naming the file (and `what` it was expected to be) otherwise or when it cannot be
// decoded; never returns an empty image.
cv::Mat read_image_file(const std::filesystem::path& file, ImageMode mode,
                        std::string_view what = "an image file");

// `image` (8- or 16-bit; 1, 3 (BGR) or 4 (BGRA) channels) as the bytes of a PNG file. Throws Error
// for other images.
std::vector<unsigned char> encode_png(const cv::Mat& image);

// Encodes `image` as PNG and writes it through write_atomically (rgbl/core/file.hpp): a reader never
// sees half a file, an interrupted writer leaves none. Throws Error naming the file.
void write_png_file(const std::filesystem::path& file, const cv::Mat& image);

// Depth in metres as the 16-bit PNG value of KITTI depth completion: round(depth * 256). 0 means no
// depth, and is also what a depth that does not fit gets (above 255.996 m, <= 0, NaN): a saturated
// 65535 would read back as a false 256 m.
cv::Mat encode_depth16(const cv::Mat_<float>& depth);

}  // namespace rgbl
