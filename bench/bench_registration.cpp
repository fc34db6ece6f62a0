#include "bench_data.hpp"
#include "reference/scan_registration_reference.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/tracking/options.hpp"

#include <benchmark/benchmark.h>

#include <vector>

namespace {

// Two keyframes' scan samples as local mapping registers them (LocalMappingOptions::lidar_registration):
// sequence 04's frames 0 and 3, ~4 m apart (its keyframes come every 3 frames), every 8th return
// within 2-40 m in the camera frame, from a guess 4 m ahead.
struct KeyframePair {
  std::vector<rgbl::LidarPoint> reference, query;
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  rgbl::ScanRegistrationOptions options = rgbl::LocalMappingOptions{}.lidar_registration;

  KeyframePair() : reference(sample(0)), query(sample(3)) { guess.translation() = Eigen::Vector3d(0.0, 0.0, 4.0); }

  static std::vector<rgbl::LidarPoint> sample(int frame) {
    return rgbl::as_points(
        rgbl::sample_scan(rgbl::bench::scan(frame), rgbl::bench::calibration().T_cam0_lidar, rgbl::ScanSampleOptions{}));
  }
};

void scan_registration_rgbl(benchmark::State& state) {
  const KeyframePair pair;
  for (auto _ : state) benchmark::DoNotOptimize(rgbl::register_scans(pair.reference, pair.query, pair.guess, pair.options));
}

void scan_registration_reference(benchmark::State& state) {
  const KeyframePair pair;
  for (auto _ : state) {
    benchmark::DoNotOptimize(rgbl::reference::register_scans(pair.reference, pair.query, pair.guess, pair.options));
  }
}

}  // namespace

BENCHMARK(scan_registration_rgbl)->Name("scan_registration/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(scan_registration_reference)->Name("scan_registration/reference")->Unit(benchmark::kMillisecond);
