#include "bench_data.hpp"
#include "reference/scan_registration_reference.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/tracking/options.hpp"

#include <benchmark/benchmark.h>

#include <memory>
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

// A gap in the frames as the tracker registers it (TrackerOptions::gap_registration): sequence 04's
// scans 14 and 35, 2.1 s apart, from a constant-velocity guess of 1.4 m per frame; the search covers
// 91 starts. Inline, and on a pool of 2 threads (the calling one and one worker), as the pipeline
// gives the tracker the pool that builds its frames.
struct GapPair {
  std::vector<rgbl::LidarPoint> reference = rgbl::bench::scan(14), query = rgbl::bench::scan(35);
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  GapPair() { guess.translation() = Eigen::Vector3d(0.0, 0.0, 1.4 * 21); }
};

void gap_registration(benchmark::State& state) {
  const GapPair pair;
  const auto threads = static_cast<int>(state.range(0));
  const auto pool = threads > 1 ? std::make_unique<rgbl::TaskPool>(threads) : nullptr;
  const rgbl::GapRegistrationOptions options;
  const Eigen::Isometry3d T_cam_lidar = rgbl::bench::calibration().T_cam0_lidar;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        rgbl::register_across_gap(pair.reference, pair.query, T_cam_lidar, pair.guess, 2.1, options, pool.get()));
  }
}

}  // namespace

BENCHMARK(gap_registration)->Name("gap_registration/inline")->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(gap_registration)->Name("gap_registration/pool")->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(scan_registration_rgbl)->Name("scan_registration/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(scan_registration_reference)->Name("scan_registration/reference")->Unit(benchmark::kMillisecond);
