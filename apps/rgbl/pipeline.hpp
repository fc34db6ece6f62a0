#pragma once
// What `rgbl run`, `rgbl depth` and `rgbl demo` share: the input options, and turning them into a
// dataset, a depth source and the system's options.

#include "rgbl/depth/registry.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/io/frame_input.hpp"
#include "rgbl/io/sequence.hpp"
#include "rgbl/tracking/system.hpp"

#include <CLI/App.hpp>

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rgbl::cli {

struct InputOptions {
  std::string dir;
  std::string format = "auto";
  int camera = -1;         // -1: camera 2 when the dataset has it, else 0
  std::size_t frames = 0;  // 0 = all
  std::size_t first = 0;
  std::size_t step = 1;    // every step-th frame
  std::string depth = "lidar";
  std::string config;      // ORB-SLAM / RGB-L style settings YAML
};

// Declares the options shared by `run` and `depth` on `app`.
void add_input_options(CLI::App& app, InputOptions& options);

// Everything a run needs, resolved and validated.
struct Pipeline {
  std::unique_ptr<Sequence> sequence;
  int camera = 0;
  CameraCalibration calibration;
  std::string depth_name;  // registry name: lidar, precomputed, stereo, stereo_sparse, rgbd
  DepthSourceSettings depth_settings;
  SystemOptions system;
  OrbOptions orb;
  std::size_t first = 0, count = 0;  // frames to process: first, first + step, ... (count of them)
  std::size_t step = 1;
  std::vector<std::string> notes;    // decisions made on the user's behalf, printed once

  std::unique_ptr<DepthSource> make_depth_source() const;
  FeatureExtractor make_extractor() const;
};

// Opens the dataset and maps --depth, --camera and --config onto the options. Throws rgbl::Error
// (ConfigError, ParseError) naming the option, file or key that is wrong.
Pipeline make_pipeline(const InputOptions& options);

// The depth source's view of one loaded frame for `camera` (images are shared, not copied).
SensorFrame sensor_frame(const FrameInput& input, int camera);

}  // namespace rgbl::cli
