#pragma once
// What `rgbl depth` does: a pipeline's depth source run over its frames, the completed maps written
// as uint16 PNG (depth x 256) with colourised previews, and graded against the dataset's own depth
// (synthetic, RGB-D) or, for LiDAR data with ground-truth poses, against the neighbouring scans
// accumulated into each frame (SPEC 3).

#include "rgbl/depth/evaluation.hpp"
#include "rgbl/pipeline/pipeline.hpp"

#include <cstddef>
#include <filesystem>
#include <optional>

namespace rgbl {

struct DepthExportOptions {
  int ground_truth_half_window = 5;  // LiDAR ground truth: the scans of +-N frames (needs poses)
  float preview_max_depth = 80.0F;   // m, the far end of the previews' colour scale

  void validate() const;  // throws ConfigError naming the option
};

struct DepthExportResult {
  std::size_t frames = 0;
  double mean_density = 0.0;  // fraction of pixels with depth
  double mean_ms = 0.0;       // per frame: prepare + dense map
  bool lidar_ground_truth = false;  // graded against accumulated scans (else the dataset's depth images)
  std::size_t graded = 0;           // frames with ground truth
  std::optional<DepthErrors> errors;
};

// Writes out_dir/depth/NNNNNN.png and out_dir/preview/NNNNNN.png for every frame of the pipeline.
DepthExportResult export_depth(const Pipeline& pipeline, const std::filesystem::path& out_dir,
                               const DepthExportOptions& options = {});

}  // namespace rgbl
