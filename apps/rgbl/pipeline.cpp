#include "pipeline.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/io/settings.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <system_error>

namespace rgbl::cli {
namespace {

// --depth: lidar | lidar:dilated | lidar:ipbasic | lidar:ipbasic-multiscale | lidar:<kernel><size>
// (e.g. lidar:diamond7) | precomputed:<dir> | stereo | stereo_sparse | rgbd
void apply_depth_spec(const std::string& spec, Pipeline& p) {
  const auto colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? std::string() : spec.substr(colon + 1);
  p.depth_name = name;
  auto& lidar = p.depth_settings.lidar;
  if (name == "lidar") {
    if (arg.empty() || arg == "dilation") return;
    if (arg == "dilated") {
      lidar.keypoint_depth = KeypointDepthRule::dilated;  // the paper's keypoint depth: the dense map's value
    } else if (arg == "ipbasic" || arg == "ipbasic-fast") {
      lidar.completion = CompletionMethod::ip_basic_fast;
    } else if (arg == "ipbasic-multiscale") {
      lidar.completion = CompletionMethod::ip_basic_multiscale;
    } else {
      // <shape><size>, e.g. diamond5, rectangle3, cross7
      const auto digit = arg.find_first_of("0123456789");
      if (digit == std::string::npos || digit == 0) {
        throw ConfigError("--depth", fmt::format("lidar, lidar:dilated, lidar:ipbasic, lidar:ipbasic-multiscale or "
                                                 "lidar:<diamond|rectangle|cross><size>, not '{}'",
                                                 spec));
      }
      lidar.dilation.shape = parse_kernel_shape(arg.substr(0, digit), "--depth");
      // std::stoi would accept "7x" and throw a bare "stoi" on overflow: parse the whole tail.
      const std::string size = arg.substr(digit);
      int value = 0;
      const auto [end, ec] = std::from_chars(size.data(), size.data() + size.size(), value);
      if (ec != std::errc() || end != size.data() + size.size() || value < 1 || value > 63 || value % 2 == 0) {
        throw ConfigError("--depth", fmt::format("an odd kernel size 1..63 after the shape (e.g. lidar:diamond5), "
                                                 "not '{}'", spec));
      }
      lidar.dilation.size = value;
    }
  } else if (name == "precomputed") {
    if (arg.empty()) throw ConfigError("--depth", "precomputed:<folder of uint16 depth PNGs>");
    p.depth_settings.precomputed.folder = arg;
  } else if (name == "stereo" || name == "stereo_sparse" || name == "rgbd") {
    if (!arg.empty()) throw ConfigError("--depth", fmt::format("'{}' without an argument", name));
  } else if (!DepthSourceRegistry::with_builtins().contains(name)) {
    throw ConfigError("--depth", fmt::format("one of lidar[:...], precomputed:<dir>, stereo, stereo_sparse, rgbd; not '{}'", spec));
  }
}

void apply_settings(const Settings& s, Pipeline& p) {
  for (const auto& w : s.warnings) p.notes.push_back(w);  // each already names the file
  p.orb.num_features = s.orb.n_features;
  p.orb.num_levels = s.orb.n_levels;
  p.orb.scale_factor = static_cast<float>(s.orb.scale_factor);
  p.orb.fast_threshold = s.orb.ini_th_fast;
  p.orb.fast_min_threshold = s.orb.min_th_fast;
  if (s.orb.features_per_node) p.orb.features_per_node = *s.orb.features_per_node;
  if (s.orb.spread_fraction) p.orb.spread_fraction = *s.orb.spread_fraction;
  p.depth_settings.lidar.projection = s.projection;
  p.depth_settings.lidar.dilation.max_depth = s.projection.max_depth;
  if (!s.lidar_method.empty() && s.lidar_method != "InverseDilation") {
    throw ConfigError("LiDAR.Method", fmt::format("InverseDilation (the only method of the reference settings "
                                                  "rgbl maps; use --depth lidar:ipbasic for IP-Basic), not '{}'",
                                                  s.lidar_method));
  }
  if (!s.kernel_type.empty()) {
    std::string shape = s.kernel_type;
    for (auto& c : shape) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    p.depth_settings.lidar.dilation.shape = parse_kernel_shape(shape, "LiDAR.MethodInverseDilation.KernelType");
  }
  if (s.kernel_size > 0) p.depth_settings.lidar.dilation.size = s.kernel_size;
  if (s.T_cam_lidar) {
    p.calibration.T_cam_lidar = *s.T_cam_lidar;
    p.notes.push_back(fmt::format("{}: LiDAR.Tr overrides the dataset's LiDAR extrinsics", s.file.string()));
  }
  if (s.camera) {
    const auto& c = *s.camera;
    const auto& d = p.calibration.camera;
    if (std::abs(c.fx - d.fx) > 1e-3 || std::abs(c.fy - d.fy) > 1e-3 || std::abs(c.cx - d.cx) > 1e-3 ||
        std::abs(c.cy - d.cy) > 1e-3) {
      p.notes.push_back(fmt::format("{}: Camera.fx/fy/cx/cy differ from the dataset's calibration; using the "
                                    "dataset's (the settings file may be for another sequence)",
                                    s.file.string()));
    }
  }
  if (s.depth_map_factor) p.depth_settings.rgbd.scale = *s.depth_map_factor;
  LoopClosingOptions& loop = p.system.loop_closing;
  const LoopClosingSettings& l = s.loop_closing;
  if (l.enabled) loop.enabled = *l.enabled;
  if (l.max_place_distance) loop.places.scan_context.max_distance = *l.max_place_distance;
  if (l.places) loop.places.methods = *l.places;
  if (l.vocabulary) loop.places.bow.vocabulary = l.vocabulary->string();
  if (l.consistent_keyframes) loop.consistent_keyframes = *l.consistent_keyframes;
  if (l.max_drift_percent) loop.max_drift_percent = *l.max_drift_percent;
  if (l.max_drift_deg_per_100m) loop.max_drift_deg_per_100m = *l.max_drift_deg_per_100m;
  if (l.fuse) loop.fuse = *l.fuse;
  if (l.global_ba) loop.global_ba = *l.global_ba;
  if (l.merge_maps) loop.merge_maps = *l.merge_maps;
  if (s.bf || s.th_depth) {
    p.notes.push_back("Camera.bf / ThDepth are not used: rgbl weights depth with an explicit noise model");
  }
}

}  // namespace

void add_input_options(CLI::App& app, InputOptions& options) {
  app.add_option("dir", options.dir, "Dataset folder: KITTI odometry sequences/NN, KITTI raw drive, or TUM RGB-D")
      ->required();
  app.add_option("--format", options.format, "Dataset layout (auto detects it)")
      ->check(CLI::IsMember({"auto", "kitti", "kitti-raw", "tum"}));
  app.add_option("--camera", options.camera, "Tracked camera: 0 (grey left, the default when present) or 2 (colour left)")
      ->check(CLI::IsMember({0, 2}));
  app.add_option("--depth", options.depth,
                 "Depth source: lidar (5x5 diamond; keypoints at their surface's mean depth), lidar:dilated "
                 "(keypoints at the dilated value, as the paper), lidar:ipbasic, lidar:ipbasic-multiscale, lidar:diamond7, "
                 "precomputed:<dir>, stereo (SGBM), stereo_sparse (keypoints only), rgbd")
      ->capture_default_str();
  app.add_option("--config", options.config, "Settings YAML (ORB-SLAM style; RGB-L LiDAR.* keys accepted)");
  app.add_option("--frames", options.frames, "Number of frames to process (default: all)");
  app.add_option("--first", options.first, "First frame to process");
  app.add_option("--step", options.step, "Process every N-th frame (e.g. 2: KITTI at 5 Hz)")
      ->check(CLI::PositiveNumber);
}

Pipeline make_pipeline(const InputOptions& options) {
  Pipeline p;
  p.sequence = open_sequence(options.dir, parse_dataset_format(options.format));
  const auto& sensors = p.sequence->sensors();
  // The tracker works on grey images: a native grey camera (0) is the default, the colour camera (2)
  // is converted per frame.
  p.camera = options.camera >= 0 ? options.camera : (sensors.cameras[0] ? 0 : 2);
  if (!sensors.cameras[static_cast<std::size_t>(p.camera)]) {
    throw ConfigError("--camera", fmt::format("a camera the dataset has ({} has no camera {})",
                                              p.sequence->path().string(), p.camera));
  }
  const KittiCalibration& kitti = p.sequence->calibration();
  p.calibration = kitti.camera(p.camera);
  p.depth_settings.calibration = p.calibration;
  if (sensors.cameras[static_cast<std::size_t>(p.camera + 1)]) {
    p.depth_settings.stereo_baseline = kitti.baseline(p.camera, p.camera + 1);
  }
  apply_depth_spec(options.depth, p);
  if (!options.config.empty()) {
    const Settings settings = read_settings(options.config);
    try {
      apply_settings(settings, p);
    } catch (const ConfigError& e) {
      throw ParseError(settings.file, 0, e.what());  // name the settings file, not just the key
    }
  }
  p.depth_settings.calibration = p.calibration;

  if (p.depth_name == "lidar" && !sensors.lidar) {
    throw ConfigError("--depth", fmt::format("a source the dataset has: {} has no LiDAR scans (try stereo or rgbd)",
                                             p.sequence->path().string()));
  }
  if ((p.depth_name == "stereo" || p.depth_name == "stereo_sparse") && !sensors.cameras[static_cast<std::size_t>(p.camera + 1)]) {
    throw ConfigError("--depth", fmt::format("{} needs camera {} (image_{}) next to camera {}", p.depth_name,
                                             p.camera + 1, p.camera + 1, p.camera));
  }
  if (p.depth_name == "rgbd" && !sensors.depth) {
    throw ConfigError("--depth", fmt::format("rgbd needs depth images: {} has none", p.sequence->path().string()));
  }
  const std::size_t size = p.sequence->size();
  if (options.first >= size) {
    throw ConfigError("--first", fmt::format("a frame index below {} (the sequence's length)", size));
  }
  if (options.step < 1) throw ConfigError("--step", "a stride of at least 1 frame");
  p.first = options.first;
  p.step = options.step;
  const std::size_t available = (size - p.first + p.step - 1) / p.step;
  p.count = options.frames == 0 ? available : std::min(options.frames, available);
  p.orb.validate();
  p.system.validate();
  // creating the source once validates its options before any frame is read
  (void)p.make_depth_source();
  return p;
}

std::unique_ptr<DepthSource> Pipeline::make_depth_source() const {
  return DepthSourceRegistry::with_builtins().create(depth_name, depth_settings);
}

FeatureExtractor Pipeline::make_extractor() const {
  auto extractor = std::make_shared<OrbExtractor>(orb);
  return [extractor](const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors) {
    extractor->extract(gray, keypoints, descriptors);
  };
}

SensorFrame sensor_frame(const FrameInput& input, int camera) {
  SensorFrame frame;
  frame.index = input.index;
  frame.timestamp = input.timestamp;
  frame.image = input.images[static_cast<std::size_t>(camera)];
  frame.image_right = input.images[static_cast<std::size_t>(camera + 1)];
  frame.depth_image = input.depth;
  frame.scan = input.scan;
  return frame;
}

}  // namespace rgbl::cli
