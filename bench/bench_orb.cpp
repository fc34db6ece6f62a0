// ORB extraction of 2000 features on a real KITTI frame: rgbl's extractor against cv::ORB.
#include "bench_data.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/features/matcher.hpp"
#include "rgbl/features/orb.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/features2d.hpp>

namespace {

// rgbl's extractor (defaults: 2000 features, 8 levels, 1.2) and cv::ORB with the same settings. With
// `threads` 1 both run on one core: OpenCV's own threading (used inside cv::resize and
// cv::GaussianBlur too) is switched off, so wall and CPU time measure the same single thread. With 2,
// rgbl's levels run on a TaskPool of 2 and OpenCV gets 2 threads of its own (timed as wall time).
void extract_rgbl(benchmark::State& state, int threads) {
  const cv::Mat img = rgbl::bench::gray_image(0);
  cv::setNumThreads(1);
  rgbl::TaskPool pool(threads);
  rgbl::OrbExtractor extractor;
  std::vector<rgbl::Keypoint> keypoints;
  std::vector<rgbl::Descriptor> descriptors;
  for (auto _ : state) {
    extractor.extract(img, keypoints, descriptors, threads > 1 ? &pool : nullptr);
    benchmark::DoNotOptimize(descriptors.data());
  }
  state.counters["features"] = static_cast<double>(keypoints.size());
}

void extract_opencv(benchmark::State& state, int threads) {
  const cv::Mat img = rgbl::bench::gray_image(0);
  cv::setNumThreads(threads);
  auto orb = cv::ORB::create(2000, 1.2F, 8);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    orb->detectAndCompute(img, cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  cv::setNumThreads(1);
  state.counters["features"] = static_cast<double>(keypoints.size());
}

void orb_rgbl(benchmark::State& state) { extract_rgbl(state, 1); }
BENCHMARK(orb_rgbl)->Name("orb/rgbl")->Unit(benchmark::kMillisecond);
void orb_opencv(benchmark::State& state) { extract_opencv(state, 1); }
BENCHMARK(orb_opencv)->Name("orb/opencv")->Unit(benchmark::kMillisecond);
void orb_rgbl_threads(benchmark::State& state) { extract_rgbl(state, static_cast<int>(state.range(0))); }
BENCHMARK(orb_rgbl_threads)->Name("orb/rgbl/threads")->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
void orb_opencv_threads(benchmark::State& state) { extract_opencv(state, static_cast<int>(state.range(0))); }
BENCHMARK(orb_opencv_threads)->Name("orb/opencv/threads")->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// Brute-force matching of two consecutive frames' 2000 descriptors (ratio test, no cross check)
// against cv::BFMatcher's 2-nearest-neighbour search with the same ratio test.
struct MatchInput {
  std::vector<rgbl::Descriptor> a, b;
  cv::Mat cv_a, cv_b;
};

MatchInput match_input() {
  MatchInput in;
  rgbl::OrbExtractor extractor;
  std::vector<rgbl::Keypoint> keypoints;
  extractor.extract(rgbl::bench::gray_image(0), keypoints, in.a);
  extractor.extract(rgbl::bench::gray_image(1), keypoints, in.b);
  in.cv_a = cv::Mat(static_cast<int>(in.a.size()), 32, CV_8UC1, in.a.data()).clone();
  in.cv_b = cv::Mat(static_cast<int>(in.b.size()), 32, CV_8UC1, in.b.data()).clone();
  return in;
}

void match_bf_rgbl(benchmark::State& state) {
  const MatchInput in = match_input();
  rgbl::BruteForceMatchOptions options;
  options.ratio = 0.8F;
  std::size_t n = 0;
  for (auto _ : state) {
    n = rgbl::match_brute_force(in.a, in.b, options).size();
    benchmark::DoNotOptimize(n);
  }
  state.counters["matches"] = static_cast<double>(n);
}
BENCHMARK(match_bf_rgbl)->Name("match_bf/rgbl")->Unit(benchmark::kMillisecond);

void match_bf_opencv(benchmark::State& state) {
  const MatchInput in = match_input();
  cv::setNumThreads(1);
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  std::size_t n = 0;
  for (auto _ : state) {
    knn.clear();  // knnMatch appends
    matcher.knnMatch(in.cv_a, in.cv_b, knn, 2);
    n = 0;
    for (const auto& m : knn) n += (m.size() == 2 && m[0].distance < 0.8F * m[1].distance && m[0].distance <= 100) ? 1 : 0;
    benchmark::DoNotOptimize(n);
  }
  state.counters["matches"] = static_cast<double>(n);
}
BENCHMARK(match_bf_opencv)->Name("match_bf/opencv")->Unit(benchmark::kMillisecond);

}  // namespace
