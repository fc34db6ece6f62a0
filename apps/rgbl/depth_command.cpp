// rgbl depth <dir> [input options] --out <dir>: completed depth maps and depth metrics (rgbl::export_depth).
#include "command.hpp"
#include "input_options.hpp"

#include "rgbl/pipeline/depth_export.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <memory>

namespace rgbl::cli {

Command add_depth_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "depth", "Write completed depth maps (uint16 PNG, depth x 256) and previews; report depth metrics");
  auto options = std::make_shared<PipelineOptions>();
  auto out_dir = std::make_shared<std::string>();
  auto depth = std::make_shared<DepthExportOptions>();
  add_input_options(*app, *options);
  app->add_option("--out", *out_dir, "Output folder (depth/ and preview/ are written inside)")->required();
  app->add_option("--gt-window", depth->ground_truth_half_window,
                  "LiDAR ground truth: accumulate the scans of +-N neighbouring frames (needs poses)")
      ->capture_default_str();
  return {app, [options, out_dir, depth] {
            const Pipeline p(*options);
            for (const auto& note : p.notes()) fmt::print(stderr, "note: {}\n", note);
            const DepthExportResult r = export_depth(p, *out_dir, *depth);
            fmt::print("{} frames, camera {}, depth {}: density {:.1f} %, {:.2f} ms per frame\n", r.frames, p.camera(),
                       options->depth, 100.0 * r.mean_density, r.mean_ms);
            if (r.errors) {
              const DepthErrors& e = *r.errors;
              fmt::print("against {} ({} frames, {} pixels, coverage {:.1f} %): MAE {:.3f} m, RMSE {:.3f} m, "
                         "iMAE {:.3f} 1/km, iRMSE {:.3f} 1/km\n",
                         r.lidar_ground_truth ? fmt::format("LiDAR scans of +-{} frames", depth->ground_truth_half_window)
                                              : "the dataset's depth",
                         r.graded, e.count, 100.0 * e.coverage, e.mae, e.rmse, e.imae, e.irmse);
            } else {
              fmt::print("no ground-truth depth (needs poses and LiDAR scans, or depth images): no metrics\n");
            }
            const std::filesystem::path out(*out_dir);
            fmt::print("depth maps in {}, previews in {}\n", (out / "depth").string(), (out / "preview").string());
            return 0;
          }};
}

}  // namespace rgbl::cli
