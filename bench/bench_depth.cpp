#include "bench_data.hpp"
#include "reference/dilation_reference.hpp"
#include "reference/occlusion_reference.hpp"
#include "reference/ring_spacing_reference.hpp"
#include "rgbl/depth/completion.hpp"
#include "rgbl/depth/ip_basic.hpp"
#include "rgbl/geometry/projection.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include <random>

namespace {

// Every kernel here runs on one core: OpenCV's own threads would otherwise give the reference two.
cv::Mat_<float> sparse_frame() {
  cv::setNumThreads(1);
  const auto cam = rgbl::bench::calibration().camera(2);
  const auto points = rgbl::bench::scan();
  return rgbl::project_to_depth(points, cam.P_img_lidar(), cam.camera.width, cam.camera.height);
}

// Keypoints where ORB finds them: anywhere in the image, uniformly, at sub-pixel positions.
std::vector<Eigen::Vector2f> keypoints(const cv::Mat& image, std::size_t count) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0F, static_cast<float>(image.cols - 1));
  std::uniform_real_distribution<float> v(0.0F, static_cast<float>(image.rows - 1));
  std::vector<Eigen::Vector2f> out(count);
  for (auto& p : out) p = {u(rng), v(rng)};
  return out;
}

void dilation_rgbl(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  const rgbl::DilationOptions options;
  cv::Mat_<float> dense(sparse.size());
  for (auto _ : state) {
    rgbl::dilate_depth(sparse, options, dense);
    benchmark::DoNotOptimize(dense.data);
    benchmark::ClobberMemory();
  }
}

void dilation_reference(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  const cv::Mat element = rgbl::Kernel::diamond(5).structuring_element();
  cv::Mat dense(sparse.size(), CV_32F);
  for (auto _ : state) {
    rgbl::reference::inverse_dilation(sparse, element, 200.0F, dense);
    benchmark::DoNotOptimize(dense.data);
    benchmark::ClobberMemory();
  }
}

// The occlusion filter on KITTI's 1241 px images: 0.3 deg is 4 px.
void occlusion_rgbl(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  cv::Mat_<float> work(sparse.size());
  cv::Mat_<float> scratch;
  for (auto _ : state) {
    sparse.copyTo(work);
    benchmark::DoNotOptimize(rgbl::remove_occluded_samples(work, 4, 1.25F, scratch));
    benchmark::ClobberMemory();
  }
}

void occlusion_reference(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  cv::Mat_<float> work(sparse.size());
  for (auto _ : state) {
    sparse.copyTo(work);
    benchmark::DoNotOptimize(rgbl::reference::remove_occluded_samples(work, 4, 1.25F));
    benchmark::ClobberMemory();
  }
}

void keypoint_depth_rgbl(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  const auto pixels = keypoints(sparse, 2000);
  std::vector<rgbl::KeypointDepth> out(pixels.size());
  const rgbl::DilationOptions options;
  for (auto _ : state) {
    rgbl::lookup_depth(sparse, options, pixels, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
}

// The dense way to the same numbers: complete the whole frame, then read the keypoints.
void keypoint_depth_reference(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  const auto pixels = keypoints(sparse, 2000);
  const cv::Mat element = rgbl::Kernel::diamond(5).structuring_element();
  std::vector<float> out(pixels.size());
  cv::Mat dense(sparse.size(), CV_32F);
  for (auto _ : state) {
    rgbl::reference::inverse_dilation(sparse, element, 200.0F, dense);
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      out[i] = dense.at<float>(static_cast<int>(pixels[i].y() + 0.5F), static_cast<int>(pixels[i].x() + 0.5F));
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
}

// The rings' spacing in the projected scan (the kernel's growth for sparser LiDARs; KITTI: 5 px).
void ring_spacing_rgbl(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  for (auto _ : state) benchmark::DoNotOptimize(rgbl::ring_spacing_px(sparse));
}

void ring_spacing_reference(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  for (auto _ : state) benchmark::DoNotOptimize(rgbl::reference::ring_spacing_px(sparse));
}

void ip_basic_fast_rgbl(benchmark::State& state) {
  const cv::Mat_<float> sparse = sparse_frame();
  for (auto _ : state) {
    cv::Mat_<float> dense = rgbl::ip_basic_fast(sparse);
    benchmark::DoNotOptimize(dense.data);
  }
}

}  // namespace

BENCHMARK(dilation_rgbl)->Name("dilation/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(dilation_reference)->Name("dilation/reference")->Unit(benchmark::kMillisecond);
BENCHMARK(occlusion_rgbl)->Name("occlusion/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(occlusion_reference)->Name("occlusion/reference")->Unit(benchmark::kMillisecond);
BENCHMARK(keypoint_depth_rgbl)->Name("keypoint_depth/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(keypoint_depth_reference)->Name("keypoint_depth/reference")->Unit(benchmark::kMillisecond);
BENCHMARK(ring_spacing_rgbl)->Name("ring_spacing/rgbl")->Unit(benchmark::kMicrosecond);
BENCHMARK(ring_spacing_reference)->Name("ring_spacing/reference")->Unit(benchmark::kMicrosecond);
BENCHMARK(ip_basic_fast_rgbl)->Name("ip_basic_fast/rgbl")->Unit(benchmark::kMillisecond);
