// Sparse stereo depth at 2000 ORB keypoints of a real KITTI pair (image_0 / image_1): the
// `stereo_sparse` source (prepare + sample) against the straightforward full-resolution SAD search.
#include "bench_data.hpp"
#include "reference/stereo_sparse_reference.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/features/orb.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include <cstdio>

namespace {

cv::Mat right_image() {
  if (const auto seq = rgbl::bench::seq04()) {
    cv::Mat img = cv::imread((*seq / "image_1" / "000000.png").string(), cv::IMREAD_GRAYSCALE);
    if (!img.empty()) return img;
  }
  // no data: the synthetic left image seen 12 px further left
  const cv::Mat left = rgbl::bench::gray_image(0);
  cv::Mat right = left.clone();
  left.colRange(12, left.cols).copyTo(right.colRange(0, left.cols - 12));
  return right;
}

std::vector<Eigen::Vector2f> orb_pixels(const cv::Mat& image) {
  rgbl::OrbExtractor extractor;
  std::vector<rgbl::Keypoint> keypoints;
  std::vector<rgbl::Descriptor> descriptors;
  extractor.extract(image, keypoints, descriptors);
  std::vector<Eigen::Vector2f> pixels;
  pixels.reserve(keypoints.size());
  for (const auto& k : keypoints) pixels.emplace_back(k.x, k.y);
  return pixels;
}

rgbl::DepthSourceContext stereo_settings() {
  const auto kitti = rgbl::bench::calibration();
  rgbl::DepthSourceContext s;
  s.calibration = kitti.camera(0);
  s.stereo_baseline = kitti.baseline(0, 1);
  if (s.stereo_baseline <= 0.0) s.stereo_baseline = 0.54;
  return s;
}

void stereo_sparse_rgbl(benchmark::State& state) {
  cv::setNumThreads(1);
  rgbl::SensorFrame frame;
  frame.image = rgbl::bench::gray_image(0);
  frame.image_right = right_image();
  const auto pixels = orb_pixels(frame.image);
  auto source = rgbl::make_stereo_sparse_source({}, stereo_settings());
  std::vector<rgbl::KeypointDepth> out(pixels.size());
  for (auto _ : state) {
    source->prepare(frame);
    source->sample(pixels, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  int with_depth = 0;
  for (const auto& d : out) with_depth += d.z > 0.0F ? 1 : 0;
  state.counters["keypoints"] = static_cast<double>(pixels.size());
  state.counters["with_depth"] = with_depth;
}
BENCHMARK(stereo_sparse_rgbl)->Name("stereo_sparse/rgbl")->Unit(benchmark::kMillisecond);

void stereo_sparse_reference(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat left = rgbl::bench::gray_image(0);
  const cv::Mat right = right_image();
  const auto pixels = orb_pixels(left);
  const auto settings = stereo_settings();
  const float fb = static_cast<float>(settings.calibration.camera.fx * settings.stereo_baseline);
  std::vector<float> depth;
  for (auto _ : state) {
    rgbl::reference::stereo_sparse(left, right, pixels, fb, 128, depth);
    benchmark::DoNotOptimize(depth.data());
    benchmark::ClobberMemory();
  }
  int with_depth = 0;
  for (const float z : depth) with_depth += z > 0.0F ? 1 : 0;
  state.counters["keypoints"] = static_cast<double>(pixels.size());
  state.counters["with_depth"] = with_depth;
}
BENCHMARK(stereo_sparse_reference)->Name("stereo_sparse/reference")->Unit(benchmark::kMillisecond);

}  // namespace
