// Loading one KITTI frame as an RGB-L run on camera 2 needs it: the colour image and the scan.
// load_frame/rgbl goes through Sequence::load (existence, size and decode checks); the reference is
// a bare cv::imread plus one read of the .bin. Both read the same files, mostly from the page cache.
#include "bench_data.hpp"
#include "rgbl/io/sequence.hpp"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include <fstream>

namespace {

void BM_load_frame_rgbl(benchmark::State& state) {
  const auto dir = rgbl::bench::seq04();
  if (!dir) {
    state.SkipWithError("no KITTI data");
    return;
  }
  rgbl::LoadOptions options;
  options.cameras = {false, false, true, false};
  const auto seq = rgbl::open_kitti_odometry(*dir, options);
  std::size_t i = 0;
  for (auto _ : state) {
    auto frame = seq->load(i);
    benchmark::DoNotOptimize(frame.scan.data());
    i = (i + 1) % seq->size();
  }
}
BENCHMARK(BM_load_frame_rgbl)->Name("load_frame/rgbl")->Unit(benchmark::kMillisecond);

void BM_load_frame_reference(benchmark::State& state) {
  const auto dir = rgbl::bench::seq04();
  if (!dir) {
    state.SkipWithError("no KITTI data");
    return;
  }
  std::size_t i = 0;
  std::vector<float> scan;
  for (auto _ : state) {
    cv::Mat image = cv::imread((*dir / "image_2" / fmt::format("{:06}.png", i)).string(), cv::IMREAD_COLOR);
    std::ifstream in(*dir / "velodyne" / fmt::format("{:06}.bin", i), std::ios::binary | std::ios::ate);
    scan.resize(static_cast<std::size_t>(in.tellg()) / sizeof(float));
    in.seekg(0);
    in.read(reinterpret_cast<char*>(scan.data()), static_cast<std::streamsize>(scan.size() * sizeof(float)));  // NOLINT
    benchmark::DoNotOptimize(image.data);
    benchmark::DoNotOptimize(scan.data());
    i = (i + 1) % 51;
  }
}
BENCHMARK(BM_load_frame_reference)->Name("load_frame/reference")->Unit(benchmark::kMillisecond);

}  // namespace
