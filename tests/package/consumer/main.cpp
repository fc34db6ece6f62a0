// A downstream program: tracks a KITTI sequence through rgbl::pipeline with a depth source of its own.
#include <rgbl/pipeline/pipeline.hpp>
#include <rgbl/version.hpp>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3) return 2;  // <sequence folder> <output folder>
  // LiDAR depth cut at <metres>: a source with an option of its own, registered here, used by name
  auto sources = rgbl::builtin_depth_sources();
  sources.add("near_lidar", {{.scan = true}, "near_lidar:<metres>", [](std::string_view arg, const auto& context) {
                               rgbl::LidarSourceOptions lidar;
                               lidar.projection.max_depth = lidar.dilation.max_depth = std::stof(std::string(arg));
                               return rgbl::make_lidar_source(lidar, context);
                             }});
  rgbl::PipelineOptions options;
  options.dataset = argv[1];
  options.frames = 30;
  options.depth = "near_lidar:60";
  const rgbl::RunResult run = rgbl::Pipeline(options, sources).run();
  rgbl::write_run_outputs(run, argv[2]);
  const double ate = run.metrics ? run.metrics->evaluation.ate.translation.rmse : 1e9;
  const bool ok = run.frames.size() == 30 && run.count(rgbl::TrackState::Ok) >= 28 && ate < 0.5;
  std::printf("rgbl %s consumer: %zu frames, %zu ok, ATE %.3f m: %s\n", RGBL_VERSION_STRING, run.frames.size(),
              run.count(rgbl::TrackState::Ok), ate, ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
