// PNG and JPEG through libpng and libjpeg directly, not OpenCV's imgcodecs: linking imgcodecs loads
// about 120 more shared libraries (GDAL, GDCM, codecs for formats no dataset here uses) at every
// process start, 0.1 s of a 1 s run. The decoders set up libpng and libjpeg the way cv::imread does, so a dataset
// decodes to the same pixels (tests/io/test_image.cpp compares them on every real image).
#include "rgbl/io/image.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <fmt/format.h>
#include <jpeglib.h>
#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

namespace rgbl {
namespace {

std::vector<unsigned char> read_bytes(const std::filesystem::path& file) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw ParseError(file, 0, fmt::format("cannot tell the image's size: {}", ec.message()));
  // 8 bytes a pixel: more than a stored (uncompressed) 16-bit colour PNG of the largest image
  if (size > 8 * kMaxImagePixels) {
    throw ParseError(file, 0, fmt::format("the file has {} bytes, more than an image rgbl reads can ({})", size,
                                          8 * kMaxImagePixels));
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ParseError(file, 0, "cannot open the image");
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  // one read of the known size: a stream iterator took a fifth of the decode time
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {  // NOLINT
    throw ParseError(file, 0, fmt::format("cannot read the image's {} bytes", size));
  }
  return bytes;
}

// ---- PNG ----
// libpng reports errors by longjmp. The functions that call setjmp hold only trivially destructible
// locals, so a longjmp out of libpng skips no destructor; they return false with the message in
// the context.

// Where a libpng error handler leaves its message: the error pointer of reader and writer alike.
struct PngMessage {
  char text[200] = {};
};

void png_error_to_message(png_structp png, png_const_charp message) {
  auto* out = static_cast<PngMessage*>(png_get_error_ptr(png));
  std::snprintf(out->text, sizeof(out->text), "%s", message);
  png_longjmp(png, 1);
}

struct PngContext {
  png_structp png = nullptr;
  png_infop info = nullptr;
  const unsigned char* data = nullptr;
  std::size_t size = 0, offset = 0;
  PngMessage message;
};

void png_ignore_warning(png_structp, png_const_charp) {}

void png_read_from_memory(png_structp png, png_bytep out, png_size_t length) {
  auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
  if (context->size - context->offset < length) png_error(png, "truncated PNG data");
  std::memcpy(out, context->data + context->offset, length);
  context->offset += length;
}

struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, colour_type = 0;
};

bool png_read_header(PngContext& c, PngHeader& header) {
  if (setjmp(png_jmpbuf(c.png)) != 0) return false;  // NOLINT(cert-err52-cpp): libpng's error model
  png_set_read_fn(c.png, &c, png_read_from_memory);
  png_read_info(c.png, c.info);
  png_get_IHDR(c.png, c.info, &header.width, &header.height, &header.bit_depth, &header.colour_type, nullptr,
               nullptr, nullptr);
  return true;
}

// The transformations of cv::imread (OpenCV 4.6, PngDecoder::readData) for an output of `channels`
// (1 or 3) at `sixteen` bits or 8.
bool png_read_rows(PngContext& c, const PngHeader& header, int channels, bool sixteen, png_bytepp rows,
                   std::size_t row_bytes) {
  if (setjmp(png_jmpbuf(c.png)) != 0) return false;  // NOLINT(cert-err52-cpp)
  if (!sixteen && header.bit_depth == 16) {
    png_set_strip_16(c.png);
  } else if (header.bit_depth == 16) {
    png_set_swap(c.png);  // PNG stores big-endian
  }
  png_set_strip_alpha(c.png);
  if (header.colour_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(c.png);
  if ((header.colour_type & PNG_COLOR_MASK_COLOR) == 0 && header.bit_depth < 8) {
    png_set_expand_gray_1_2_4_to_8(c.png);
  }
  if ((header.colour_type & PNG_COLOR_MASK_COLOR) != 0 && channels == 3) {
    png_set_bgr(c.png);
  } else if (channels == 3) {
    png_set_gray_to_rgb(c.png);
  } else {
    png_set_rgb_to_gray(c.png, 1, 0.299, 0.587);
  }
  png_set_interlace_handling(c.png);
  png_read_update_info(c.png, c.info);
  if (png_get_rowbytes(c.png, c.info) != row_bytes) {
    std::snprintf(c.message.text, sizeof(c.message.text), "unexpected row size after conversion");
    return false;
  }
  png_read_image(c.png, rows);
  png_read_end(c.png, nullptr);
  return true;
}

class PngReader {
 public:
  PngReader(const unsigned char* data, std::size_t size) {
    context_.data = data;
    context_.size = size;
    context_.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context_.message, png_error_to_message,
                                          png_ignore_warning);
    if (context_.png != nullptr) context_.info = png_create_info_struct(context_.png);
  }
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;
  ~PngReader() { png_destroy_read_struct(&context_.png, &context_.info, nullptr); }

  PngContext& context() { return context_; }
  bool ok() const { return context_.png != nullptr && context_.info != nullptr; }

 private:
  PngContext context_;
};

cv::Mat decode_png(const std::filesystem::path& file, const std::vector<unsigned char>& bytes, ImageMode mode) {
  PngReader reader(bytes.data(), bytes.size());
  if (!reader.ok()) throw Error(fmt::format("{}: cannot set up the PNG decoder", file.string()));
  PngContext& c = reader.context();
  PngHeader header;
  // (its size was checked against kMaxImagePixels by require_image_file; libpng refuses a zero size)
  if (!png_read_header(c, header)) {
    throw ParseError(file, 0, fmt::format("cannot read or decode the PNG ({})", c.message.text));
  }
  const int channels = mode == ImageMode::colour ? 3 : 1;
  const bool sixteen = mode == ImageMode::grey_any_depth && header.bit_depth == 16;
  cv::Mat image(static_cast<int>(header.height), static_cast<int>(header.width),
                CV_MAKETYPE(sixteen ? CV_16U : CV_8U, channels));
  std::vector<png_bytep> rows(header.height);
  for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = image.ptr(y);
  if (!png_read_rows(c, header, channels, sixteen, rows.data(), image.cols * image.elemSize())) {
    throw ParseError(file, 0,
                     fmt::format("cannot read or decode the PNG ({}; corrupt or truncated?)", c.message.text));
  }
  return image;
}

// ---- JPEG ----
// libjpeg, like libpng, reports errors through a callback that must not return: the same setjmp
// discipline.

struct JpegError {
  jpeg_error_mgr manager{};
  std::jmp_buf jump{};
  char message[JMSG_LENGTH_MAX] = {};
};

void jpeg_error_exit_to_jump(j_common_ptr info) {
  auto* error = reinterpret_cast<JpegError*>(info->err);  // NOLINT: manager is the first member
  (*info->err->format_message)(info, error->message);
  std::longjmp(error->jump, 1);
}

void jpeg_no_output(j_common_ptr) {}

bool jpeg_read_header_into(jpeg_decompress_struct& info, JpegError& error, const unsigned char* data,
                           std::size_t size) {
  if (setjmp(error.jump) != 0) return false;  // NOLINT(cert-err52-cpp)
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  return true;
}

// Separate from the header: a progressive JPEG allocates buffers for the whole image here, so its
// size is checked first.
bool jpeg_start(jpeg_decompress_struct& info, JpegError& error, bool colour) {
  if (setjmp(error.jump) != 0) return false;  // NOLINT(cert-err52-cpp)
  // As cv::imread (OpenCV 4.6, JpegDecoder::readData) for 1- and 3-component files.
  info.out_color_space = colour ? JCS_EXT_BGR : JCS_GRAYSCALE;
  info.out_color_components = colour ? 3 : 1;
  jpeg_start_decompress(&info);
  return true;
}

bool jpeg_read_rows(jpeg_decompress_struct& info, JpegError& error, unsigned char* data, std::size_t step) {
  if (setjmp(error.jump) != 0) return false;  // NOLINT(cert-err52-cpp)
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = data + step * info.output_scanline;
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  return true;
}

class JpegReader {
 public:
  JpegReader() {
    info_.err = jpeg_std_error(&error_.manager);
    error_.manager.error_exit = jpeg_error_exit_to_jump;
    error_.manager.output_message = jpeg_no_output;
  }
  JpegReader(const JpegReader&) = delete;
  JpegReader& operator=(const JpegReader&) = delete;
  ~JpegReader() { jpeg_destroy_decompress(&info_); }

  jpeg_decompress_struct& info() { return info_; }
  JpegError& error() { return error_; }

 private:
  jpeg_decompress_struct info_{};
  JpegError error_;
};

cv::Mat decode_jpeg(const std::filesystem::path& file, const std::vector<unsigned char>& bytes, ImageMode mode) {
  JpegReader reader;
  const bool colour = mode == ImageMode::colour;
  if (!jpeg_read_header_into(reader.info(), reader.error(), bytes.data(), bytes.size())) {
    throw ParseError(file, 0, fmt::format("cannot read or decode the JPEG ({})", reader.error().message));
  }
  const jpeg_decompress_struct& info = reader.info();
  if (info.num_components != 1 && info.num_components != 3) {
    throw ParseError(file, 0, fmt::format("a JPEG with {} components (rgbl reads grey and colour ones)",
                                          info.num_components));
  }
  if (std::uint64_t{info.image_width} * info.image_height > kMaxImagePixels) {
    throw ParseError(file, 0, fmt::format("JPEG of {}x{} pixels: more than rgbl reads", info.image_width,
                                          info.image_height));
  }
  if (!jpeg_start(reader.info(), reader.error(), colour)) {
    throw ParseError(file, 0, fmt::format("cannot read or decode the JPEG ({})", reader.error().message));
  }
  cv::Mat image(static_cast<int>(info.output_height), static_cast<int>(info.output_width), colour ? CV_8UC3 : CV_8UC1);
  if (!jpeg_read_rows(reader.info(), reader.error(), image.data, image.step)) {
    throw ParseError(file, 0,
                     fmt::format("cannot read or decode the JPEG ({}; corrupt or truncated?)", reader.error().message));
  }
  return image;
}

// ---- PNG encoding ----

struct PngWriteContext {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::vector<unsigned char>* out = nullptr;
  PngMessage message;
};

void png_write_to_vector(png_structp png, png_bytep data, png_size_t length) {
  auto* context = static_cast<PngWriteContext*>(png_get_io_ptr(png));
  context->out->insert(context->out->end(), data, data + length);  // may throw bad_alloc: rare, fatal
}

void png_flush_nothing(png_structp) {}

bool png_write_rows(PngWriteContext& c, const cv::Mat& image, png_bytepp rows) {
  if (setjmp(png_jmpbuf(c.png)) != 0) return false;  // NOLINT(cert-err52-cpp)
  png_set_write_fn(c.png, &c, png_write_to_vector, png_flush_nothing);
  // Fast settings, as cv::imencode's defaults: datasets are written once and read many times, and
  // level 1 with run-length strategy is what OpenCV writes.
  png_set_compression_level(c.png, 1);
  png_set_compression_strategy(c.png, 3);  // Z_RLE
  const int colour_type = image.channels() == 1 ? PNG_COLOR_TYPE_GRAY
                          : image.channels() == 3 ? PNG_COLOR_TYPE_RGB
                                                  : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(c.png, c.info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows),
               image.depth() == CV_16U ? 16 : 8, colour_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(c.png, c.info);
  if (image.channels() >= 3) png_set_bgr(c.png);
  if (image.depth() == CV_16U) png_set_swap(c.png);
  png_write_image(c.png, rows);
  png_write_end(c.png, c.info);
  return true;
}

}  // namespace

cv::Mat read_image_file(const std::filesystem::path& file, ImageMode mode, std::string_view what) {
  require_image_file(file, what);  // a PNG or JPEG by its first bytes, within the size limit
  const std::vector<unsigned char> bytes = read_bytes(file);
  const bool jpeg = bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF;
  return jpeg ? decode_jpeg(file, bytes, mode) : decode_png(file, bytes, mode);
}

std::vector<unsigned char> encode_png(const cv::Mat& image) {
  const bool supported = !image.empty() && (image.depth() == CV_8U || image.depth() == CV_16U) &&
                         (image.channels() == 1 || image.channels() == 3 || image.channels() == 4);
  if (!supported) {
    throw Error(fmt::format("cannot encode a PNG of this image ({}x{}, type {}; expected 8- or 16-bit with 1, 3 "
                            "or 4 channels)",
                            image.cols, image.rows, image.type()));
  }
  std::vector<unsigned char> out;
  PngWriteContext c;
  c.out = &out;
  c.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &c.message, png_error_to_message, png_ignore_warning);
  if (c.png != nullptr) c.info = png_create_info_struct(c.png);
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) {
    rows[static_cast<std::size_t>(y)] = const_cast<png_bytep>(image.ptr(y));  // NOLINT: libpng takes non-const rows
  }
  const bool ok = c.info != nullptr && png_write_rows(c, image, rows.data());
  png_destroy_write_struct(&c.png, &c.info);
  if (!ok) throw Error(fmt::format("cannot encode a PNG of this image ({})", c.message.text));
  return out;
}

void write_png_file(const std::filesystem::path& file, const cv::Mat& image) {
  std::vector<unsigned char> png;
  try {
    png = encode_png(image);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", file.string(), e.what()));
  }
  write_atomically(file, png);
}

cv::Mat encode_depth16(const cv::Mat_<float>& depth) {
  cv::Mat_<std::uint16_t> out(depth.rows, depth.cols);
  for (int v = 0; v < depth.rows; ++v) {
    const float* in = depth[v];
    std::uint16_t* row = out[v];
    for (int u = 0; u < depth.cols; ++u) {
      const double scaled = std::round(static_cast<double>(in[u]) * 256.0);
      row[u] = scaled > 0.0 && scaled <= 65535.0 ? static_cast<std::uint16_t>(scaled) : 0;
    }
  }
  return out;
}

}  // namespace rgbl
