#pragma once
// Tiny synthetic datasets written by the tests themselves (a few hundred bytes each).

#include "support/temp_dir.hpp"

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace rgbl::test {

inline const char* kSmallCalib =
    "P0: 50 0 3.5 0 0 50 2.5 0 0 0 1 0\n"
    "P1: 50 0 3.5 -25 0 50 2.5 0 0 0 1 0\n"
    "P2: 50 0 3.5 3 0 50 2.5 0 0 0 1 0\n"
    "P3: 50 0 3.5 -22 0 50 2.5 0 0 0 1 0\n"
    "Tr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n";

inline void write_png(const std::filesystem::path& file, int width, int height, int channels, int value) {
  std::filesystem::create_directories(file.parent_path());
  cv::Mat image(height, width, channels == 1 ? CV_8UC1 : CV_8UC3, cv::Scalar::all(value));
  cv::imwrite(file.string(), image);
}

inline void write_bin(const std::filesystem::path& file, const std::vector<float>& values) {
  std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(values.data()),  // NOLINT
            static_cast<std::streamsize>(values.size() * sizeof(float)));
}

// sequences/07 with image_0, image_2, velodyne and `frames` frames of 8x6 images; poses/07.txt with
// `poses` identity-rotation poses moving 1 m along z per frame (none when poses == 0).
struct SyntheticKitti {
  TempDir root;
  std::filesystem::path dir;

  explicit SyntheticKitti(std::size_t frames = 3, std::size_t poses = 3) {
    dir = root.path() / "sequences" / "07";
    root.write("sequences/07/calib.txt", kSmallCalib);
    std::string times;
    for (std::size_t i = 0; i < frames; ++i) {
      times += fmt::format("{:e}\n", 0.1 * static_cast<double>(i));
      write_png(dir / "image_0" / fmt::format("{:06}.png", i), 8, 6, 1, 10 + static_cast<int>(i));
      write_png(dir / "image_2" / fmt::format("{:06}.png", i), 8, 6, 3, 20 + static_cast<int>(i));
      write_bin(dir / "velodyne" / fmt::format("{:06}.bin", i), {10.0F, 0.0F, 0.0F, 0.5F, 20.0F, 1.0F, 0.0F, 0.25F});
    }
    root.write("sequences/07/times.txt", times);
    if (poses > 0) {
      std::string rows;
      for (std::size_t i = 0; i < poses; ++i) rows += fmt::format("1 0 0 0 0 1 0 0 0 0 1 {}\n", i);
      root.write("poses/07.txt", rows);
    }
  }
  std::filesystem::path image0(std::size_t i) const { return dir / "image_0" / fmt::format("{:06}.png", i); }
  std::filesystem::path scan(std::size_t i) const { return dir / "velodyne" / fmt::format("{:06}.bin", i); }
};

}  // namespace rgbl::test
