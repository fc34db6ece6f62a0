// rgbl's PNG and JPEG codec (libpng and libjpeg directly) against cv::imread and cv::imwrite: the same
// pixels, the same type, for every mode, on real KITTI frames and on synthetic images of every
// layout the loaders meet.
#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"

#include "support/data.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace {

constexpr std::pair<rgbl::ImageMode, int> kModes[] = {{rgbl::ImageMode::grey, cv::IMREAD_GRAYSCALE},
                                                      {rgbl::ImageMode::colour, cv::IMREAD_COLOR},
                                                      {rgbl::ImageMode::grey_any_depth, cv::IMREAD_ANYDEPTH}};

// Empty when equal, else what differs.
std::string difference(const cv::Mat& ours, const cv::Mat& opencv) {
  if (ours.size() != opencv.size() || ours.type() != opencv.type()) {
    return "size or type: " + std::to_string(ours.cols) + "x" + std::to_string(ours.rows) + " type " +
           std::to_string(ours.type()) + " against " + std::to_string(opencv.cols) + "x" +
           std::to_string(opencv.rows) + " type " + std::to_string(opencv.type());
  }
  const double max_difference = cv::norm(ours, opencv, cv::NORM_INF);
  return max_difference == 0.0 ? std::string() : "pixels differ by up to " + std::to_string(max_difference);
}

void check_same_as_opencv(const std::filesystem::path& file) {
  for (const auto& [mode, flags] : kModes) {
    INFO(file.string() << " mode " << static_cast<int>(mode));
    const cv::Mat ours = rgbl::read_image_file(file, mode);
    const cv::Mat theirs = cv::imread(file.string(), flags);
    REQUIRE(!theirs.empty());
    CHECK(difference(ours, theirs).empty());
  }
}

cv::Mat random_image(int rows, int cols, int type, unsigned seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  // smooth areas as well as noise, as in a photograph
  image(cv::Rect(0, 0, cols / 2, rows / 2)).setTo(cv::Scalar::all(CV_MAT_DEPTH(type) == CV_16U ? 40000 : 90));
  return image;
}

}  // namespace

TEST_CASE("every real KITTI frame decodes to cv::imread's pixels in every mode") {
  const auto root = rgbl::test::find_data("kitti");
  if (!root) return;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(*root)) {
    if (entry.is_regular_file() && entry.path().extension() == ".png") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() >= 100);
  for (const auto& file : files) check_same_as_opencv(file);
}

TEST_CASE("synthetic PNGs and JPEGs of every layout decode to cv::imread's pixels") {
  const rgbl::test::TempDir dir;
  int index = 0;
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3}) {
    const auto file = dir.path() / ("image" + std::to_string(index) + ".png");
    REQUIRE(cv::imwrite(file.string(), random_image(37, 53, type, static_cast<unsigned>(++index))));
    check_same_as_opencv(file);
  }
  // (cv::imwrite writes no interlaced, palette or 1-bit PNG, so those layouts are not compared here)
  // JPEGs: grey and colour, baseline and progressive
  for (const int type : {CV_8UC1, CV_8UC3}) {
    for (const int progressive : {0, 1}) {
      const auto file = dir.path() / ("image" + std::to_string(++index) + ".jpg");
      REQUIRE(cv::imwrite(file.string(), random_image(41, 67, type, static_cast<unsigned>(index)),
                          {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_PROGRESSIVE, progressive}));
      for (const auto& [mode, flags] : kModes) {
        INFO(file.string() << " mode " << static_cast<int>(mode));
        CHECK(difference(rgbl::read_image_file(file, mode), cv::imread(file.string(), flags)).empty());
      }
    }
  }
}

TEST_CASE("write_png_file writes PNGs that read back exactly, by rgbl and by OpenCV") {
  const rgbl::test::TempDir dir;
  for (const int type : {CV_8UC1, CV_8UC3, CV_16UC1}) {
    const cv::Mat image = random_image(29, 31, type, 7U + static_cast<unsigned>(type));
    const auto file = dir.path() / ("out" + std::to_string(type) + ".png");
    rgbl::write_png_file(file, image);
    CHECK(difference(cv::imread(file.string(), cv::IMREAD_UNCHANGED), image).empty());
    const rgbl::ImageMode mode = image.channels() == 3 ? rgbl::ImageMode::colour : rgbl::ImageMode::grey_any_depth;
    CHECK(difference(rgbl::read_image_file(file, mode), image).empty());
  }
  // BGRA: the alpha channel is written (OpenCV reads it back unchanged)
  const cv::Mat bgra = random_image(9, 11, CV_8UC4, 3);
  const auto file = dir.path() / "bgra.png";
  rgbl::write_png_file(file, bgra);
  CHECK(difference(cv::imread(file.string(), cv::IMREAD_UNCHANGED), bgra).empty());
  // what PNG cannot hold is an error naming the file
  CHECK_THROWS_WITH(rgbl::write_png_file(dir.path() / "float.png", cv::Mat(4, 4, CV_32F, cv::Scalar(1.0))),
                    Catch::Contains("float.png") && Catch::Contains("expected 8- or 16-bit"));
  CHECK_THROWS_AS(rgbl::encode_png(cv::Mat()), rgbl::Error);
}

TEST_CASE("a damaged PNG or JPEG is a ParseError naming the file, never a crash") {
  const rgbl::test::TempDir dir;
  const cv::Mat image = random_image(64, 64, CV_8UC3, 11);
  std::vector<unsigned char> png, jpeg;
  REQUIRE(cv::imencode(".png", image, png));
  REQUIRE(cv::imencode(".jpg", image, jpeg));
  for (const auto& [name, bytes] : {std::pair{std::string("png"), png}, std::pair{std::string("jpg"), jpeg}}) {
    // truncated after the header, and with its middle overwritten
    const auto half = static_cast<long>(bytes.size() / 2);
    std::vector<std::string> damaged = {std::string(bytes.begin(), bytes.begin() + 40),
                                        std::string(bytes.begin(), bytes.begin() + half)};
    std::string scrambled(bytes.begin(), bytes.end());
    std::mt19937 rng(5);
    for (std::size_t i = scrambled.size() / 4; i < scrambled.size() * 3 / 4; ++i) {
      scrambled[i] = static_cast<char>(rng());
    }
    if (name == "png") damaged.push_back(scrambled);  // a JPEG decoder conceals damage (as OpenCV's does)
    int index = 0;
    for (const std::string& contents : damaged) {
      const auto file = dir.write("damaged" + std::to_string(++index) + "." + name, contents);
      INFO(file.string());
      if (name == "jpg" && index == 2) {
        // half a JPEG: libjpeg fills the rest with grey and warns, as for cv::imread
        CHECK(rgbl::read_image_file(file, rgbl::ImageMode::grey).rows == 64);
        continue;
      }
      CHECK_THROWS_WITH(rgbl::read_image_file(file, rgbl::ImageMode::colour),
                        Catch::Contains(file.filename().string()) && Catch::Contains("cannot read or decode"));
    }
  }
}
