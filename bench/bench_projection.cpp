#include "bench_data.hpp"
#include "reference/projection_reference.hpp"
#include "rgbl/geometry/projection.hpp"

#include <benchmark/benchmark.h>

namespace {

void projection_rgbl(benchmark::State& state) {
  const auto calib = rgbl::bench::calibration();
  const auto cam = calib.camera(2);
  const auto points = rgbl::bench::scan();
  const rgbl::Matrix34d P = cam.P_img_lidar();
  const rgbl::ProjectionOptions options;
  cv::Mat_<float> depth(cam.camera.height, cam.camera.width);
  for (auto _ : state) {
    benchmark::DoNotOptimize(rgbl::project_to_depth(points, P, options, depth));
    benchmark::ClobberMemory();
  }
  state.counters["points"] = static_cast<double>(points.size());
}

void projection_reference(benchmark::State& state) {
  const auto calib = rgbl::bench::calibration();
  const auto cam = calib.camera(2);
  const auto points = rgbl::bench::scan();
  const rgbl::Matrix34d P = cam.P_img_lidar();
  const cv::Mat X = rgbl::reference::to_homogeneous_matrix(points);
  cv::Mat depth(cam.camera.height, cam.camera.width, CV_32F);
  for (auto _ : state) {
    rgbl::reference::project_to_depth(X, P, 5.0F, 200.0F, depth);
    benchmark::DoNotOptimize(depth.data);
    benchmark::ClobberMemory();
  }
  state.counters["points"] = static_cast<double>(points.size());
}

}  // namespace

BENCHMARK(projection_rgbl)->Name("projection/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(projection_reference)->Name("projection/reference")->Unit(benchmark::kMillisecond);
