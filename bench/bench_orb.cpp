// ORB extraction of 2000 features on a real KITTI frame: rgbl's extractor against cv::ORB.
#include "bench_data.hpp"
#include "rgbl/features/orb.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/features2d.hpp>

namespace {

void orb_rgbl(benchmark::State& state) {
  const cv::Mat img = rgbl::bench::gray_image(0);
  rgbl::OrbExtractor extractor;  // defaults: 2000 features, 8 levels, 1.2
  std::vector<rgbl::Keypoint> keypoints;
  std::vector<rgbl::Descriptor> descriptors;
  for (auto _ : state) {
    extractor.extract(img, keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data());
  }
  state.counters["features"] = static_cast<double>(keypoints.size());
}
BENCHMARK(orb_rgbl)->Name("orb/rgbl")->Unit(benchmark::kMillisecond);

void orb_opencv(benchmark::State& state) {
  const cv::Mat img = rgbl::bench::gray_image(0);
  cv::setNumThreads(1);
  auto orb = cv::ORB::create(2000, 1.2F, 8);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    orb->detectAndCompute(img, cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["features"] = static_cast<double>(keypoints.size());
}
BENCHMARK(orb_opencv)->Name("orb/opencv")->Unit(benchmark::kMillisecond);

}  // namespace
