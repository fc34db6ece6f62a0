// rgbl_learn_brief_pattern <image> [<image> ...] > src/features/brief_pattern_indices.inc
// Chooses the extractor's 256 BRIEF tests among the first 4096 candidates of make_brief_candidates(31)
// by the ORB paper's criterion: on steered patches around real keypoints, prefer tests whose mean is
// near 0.5 (high variance) and greedily keep those whose correlation with every test kept so far is
// below a threshold (raised in steps until 256 are found). Prints the C++ include on stdout.
// The project's table was learned on the grey images of KITTI raw drive 2011_09_26_0009 (image_00),
// a different place than the odometry sequence 04 used for evaluation; see docs/features.md.
#include "rgbl/features/orb.hpp"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <exception>
#include <numeric>
#include <vector>

namespace {

constexpr int kPool = 4096;

int round_to_int(float v) { return static_cast<int>(v + (v >= 0.0F ? 0.5F : -0.5F)); }

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 2) {
      fmt::print(stderr, "usage: rgbl_learn_brief_pattern <image> [<image> ...]\n");
      return 2;
    }
    const rgbl::OrbOptions options;
    const auto pool = rgbl::make_brief_candidates(options.patch_size, kPool);
    rgbl::OrbExtractor extractor(options);
    // bits[t] holds test t's outcome on every training patch, packed 64 patches per word.
    std::vector<std::vector<std::uint64_t>> bits(kPool);
    std::size_t patches = 0;
    std::vector<rgbl::Keypoint> keypoints;
    std::vector<rgbl::Descriptor> descriptors;
    cv::Mat blurred;
    for (int i = 1; i < argc; ++i) {
      const cv::Mat img = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
      if (img.empty()) throw std::runtime_error(fmt::format("cannot read {}", argv[i]));
      extractor.extract(img, keypoints, descriptors);
      std::vector<cv::Mat> smoothed;
      for (const auto& level : extractor.pyramid()) {
        cv::GaussianBlur(level, blurred, cv::Size(options.blur_size, options.blur_size), options.blur_sigma,
                         options.blur_sigma, cv::BORDER_REFLECT_101);
        smoothed.push_back(blurred.clone());
      }
      for (const auto& k : keypoints) {
        const cv::Mat& level = smoothed[static_cast<std::size_t>(k.level)];
        const rgbl::LevelMap& m = extractor.level_maps()[static_cast<std::size_t>(k.level)];
        const int cx = round_to_int(m.level_x(k.x)), cy = round_to_int(m.level_y(k.y));
        const float a = k.angle * 3.14159265358979323846F / 180.0F;
        const float ca = std::cos(a), sa = std::sin(a);
        const std::size_t word = patches / 64, bit = patches % 64;
        for (int t = 0; t < kPool; ++t) {
          const auto& p = pool[static_cast<std::size_t>(t)];
          const int v1 = level.at<std::uint8_t>(cy + round_to_int(p.x1 * sa + p.y1 * ca), cx + round_to_int(p.x1 * ca - p.y1 * sa));
          const int v2 = level.at<std::uint8_t>(cy + round_to_int(p.x2 * sa + p.y2 * ca), cx + round_to_int(p.x2 * ca - p.y2 * sa));
          auto& b = bits[static_cast<std::size_t>(t)];
          if (b.size() <= word) b.resize(word + 1, 0);
          if (v1 < v2) b[word] |= std::uint64_t{1} << bit;
        }
        ++patches;
      }
    }
    for (auto& b : bits) b.resize((patches + 63) / 64, 0);
    const double n = static_cast<double>(patches);
    std::vector<double> mean(kPool);
    for (int t = 0; t < kPool; ++t) {
      std::size_t ones = 0;
      for (const auto w : bits[static_cast<std::size_t>(t)]) ones += static_cast<std::size_t>(std::popcount(w));
      mean[static_cast<std::size_t>(t)] = static_cast<double>(ones) / n;
    }
    std::vector<int> order(kPool);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return std::abs(mean[static_cast<std::size_t>(a)] - 0.5) < std::abs(mean[static_cast<std::size_t>(b)] - 0.5);
    });
    auto correlation = [&](int a, int b) {
      std::size_t both = 0;
      const auto& ba = bits[static_cast<std::size_t>(a)];
      const auto& bb = bits[static_cast<std::size_t>(b)];
      for (std::size_t w = 0; w < ba.size(); ++w) both += static_cast<std::size_t>(std::popcount(ba[w] & bb[w]));
      const double pa = mean[static_cast<std::size_t>(a)], pb = mean[static_cast<std::size_t>(b)];
      const double denom = std::sqrt(pa * (1 - pa) * pb * (1 - pb));
      return denom > 0 ? (static_cast<double>(both) / n - pa * pb) / denom : 1.0;
    };
    std::vector<int> chosen;
    double threshold = 0.1;
    for (; threshold < 1.0; threshold += 0.02) {
      chosen.clear();
      for (const int t : order) {
        if (std::abs(mean[static_cast<std::size_t>(t)] - 0.5) > 0.35) break;  // near-constant tests say nothing
        bool independent = true;
        for (const int c : chosen) {
          if (std::abs(correlation(t, c)) > threshold) {
            independent = false;
            break;
          }
        }
        if (independent) chosen.push_back(t);
        if (chosen.size() == 256) break;
      }
      if (chosen.size() == 256) break;
    }
    if (chosen.size() != 256) throw std::runtime_error("could not choose 256 tests");
    fmt::print("// Generated by rgbl_learn_brief_pattern from {} patches of {} image(s); correlation threshold {:.2f}.\n"
               "// Indices into make_brief_candidates(31, kLearnedPoolSize), in order of selection.\n"
               "constexpr int kLearnedPoolSize = {};\nconstexpr std::array<std::uint16_t, 256> kLearnedPairs{{\n",
               patches, argc - 1, threshold, kPool);
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      fmt::print("{}{}{}", i % 16 == 0 ? "    " : " ", chosen[i], i + 1 == chosen.size() ? "" : ",");
      if (i % 16 == 15) fmt::print("\n");
    }
    fmt::print("}};\n");
    fmt::print(stderr, "{} patches, threshold {:.2f}\n", patches, threshold);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_learn_brief_pattern: {}\n", e.what());
    return 1;
  }
}
