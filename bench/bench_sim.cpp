// Cost of one synthetic frame (rgbl::sim): four images with 2x2 supersampling, the exact depth image
// and a 64-beam scan, at the default half-KITTI size. Argument: threads. There is no reference
// implementation to race: the figure to meet is "well under 0.5 s per frame".
#include "rgbl/sim/synthetic.hpp"

#include <benchmark/benchmark.h>

namespace {

void sim_frame_rgbl(benchmark::State& state) {
  rgbl::SyntheticOptions options;
  options.frames = 20;
  options.threads = static_cast<int>(state.range(0));
  const rgbl::SyntheticGenerator generator(options);
  int frame = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(generator.render(frame));
    frame = (frame + 1) % options.frames;
  }
}

void sim_image_rgbl(benchmark::State& state) {  // one camera image alone, one thread
  rgbl::SyntheticOptions options;
  options.frames = 20;
  options.threads = 1;
  const rgbl::SyntheticGenerator generator(options);
  int frame = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(generator.render_image(frame, 2));
    frame = (frame + 1) % options.frames;
  }
}

void sim_scan_rgbl(benchmark::State& state) {  // one LiDAR scan alone, one thread
  rgbl::SyntheticOptions options;
  options.frames = 20;
  options.threads = 1;
  const rgbl::SyntheticGenerator generator(options);
  int frame = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(generator.render_scan(frame));
    frame = (frame + 1) % options.frames;
  }
}

}  // namespace

BENCHMARK(sim_frame_rgbl)->Name("sim_frame/rgbl")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(sim_image_rgbl)->Name("sim_image/rgbl")->Unit(benchmark::kMillisecond);
BENCHMARK(sim_scan_rgbl)->Name("sim_scan/rgbl")->Unit(benchmark::kMillisecond);
