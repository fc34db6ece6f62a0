#include "rgbl/pipeline/pipeline.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/io/settings.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <shared_mutex>

namespace rgbl {
namespace {

struct Resolved {
  CameraCalibration& calibration;
  LidarSourceOptions& lidar;
  RgbdSourceOptions& rgbd;
  SystemOptions& system;
  OrbOptions& orb;
  std::vector<std::string>& notes;
};

void apply_settings(const Settings& s, Resolved p) {
  for (const auto& w : s.warnings) p.notes.push_back(w);  // each already names the file
  p.orb.num_features = s.orb.n_features;
  p.orb.num_levels = s.orb.n_levels;
  p.orb.scale_factor = static_cast<float>(s.orb.scale_factor);
  p.orb.fast_threshold = s.orb.ini_th_fast;
  p.orb.fast_min_threshold = s.orb.min_th_fast;
  if (s.orb.features_per_node) p.orb.features_per_node = *s.orb.features_per_node;
  if (s.orb.spread_fraction) p.orb.spread_fraction = *s.orb.spread_fraction;
  p.lidar.projection = s.projection;
  p.lidar.dilation.max_depth = s.projection.max_depth;
  if (!s.lidar_method.empty() && s.lidar_method != "InverseDilation") {
    throw ConfigError("LiDAR.Method", fmt::format("InverseDilation (the only method of the reference settings "
                                                  "rgbl maps; use --depth lidar:ipbasic for IP-Basic), not '{}'",
                                                  s.lidar_method));
  }
  if (!s.kernel_type.empty()) {
    std::string shape = s.kernel_type;
    for (auto& c : shape) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    p.lidar.dilation.shape = parse_kernel_shape(shape, "LiDAR.MethodInverseDilation.KernelType");
  }
  if (s.kernel_size > 0) p.lidar.dilation.size = s.kernel_size;
  if (s.kernel_from_ring_spacing) p.lidar.kernel_from_ring_spacing = *s.kernel_from_ring_spacing;
  if (s.occlusion_window_deg) p.lidar.occlusion_window_deg = *s.occlusion_window_deg;
  if (s.occlusion_ratio) p.lidar.occlusion_ratio = static_cast<float>(*s.occlusion_ratio);
  if (s.surface_fit_window_deg) p.lidar.surface_fit_window_deg = *s.surface_fit_window_deg;
  if (s.surface_step_px) p.lidar.surface_step_px = *s.surface_step_px;
  if (s.registration_sigma_deg) p.system.depth_noise.registration_sigma_deg = *s.registration_sigma_deg;
  if (s.scan_time_offset) p.system.scan_time_offset = *s.scan_time_offset;
  if (s.elevation_correction_deg) p.system.tracker.scan_sample.elevation_correction_deg = *s.elevation_correction_deg;
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
  if (s.depth_map_factor) p.rgbd.scale = *s.depth_map_factor;
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
  if (l.scans) loop.scans.enabled = *l.scans;
  if (l.bridge) loop.bridge.enabled = *l.bridge;
  if (l.bridge_max_gap_s) loop.bridge.max_gap_s = *l.bridge_max_gap_s;
  if (s.place_culling) p.system.mapping.place_culling = *s.place_culling;
  if (s.lidar_pair_sigma) p.system.mapping.pairs.lidar_sigma_translation = *s.lidar_pair_sigma;
  if (s.lidar_pair_sigma_rotation) p.system.mapping.pairs.lidar_sigma_rotation = *s.lidar_pair_sigma_rotation;
  if (s.lidar_pair_agreeing_sigma) p.system.mapping.pairs.lidar_agreeing_sigma_translation = *s.lidar_pair_agreeing_sigma;
  if (s.reference_landmark_ratio) p.system.tracker.reference_landmark_ratio = *s.reference_landmark_ratio;
  if (s.bounded_depth_error) p.system.tracker.pose.bounded_depth_error = *s.bounded_depth_error;
  if (s.cauchy_weights) p.system.tracker.pose.cauchy = *s.cauchy_weights;
  if (s.object_test) p.system.tracker.object_test = *s.object_test;
  if (s.direction_prior) p.system.tracker.direction_prior = *s.direction_prior;
  if (s.register_gaps) p.system.tracker.register_gaps = *s.register_gaps;
  if (s.register_lost) p.system.tracker.register_lost = *s.register_lost;
  if (s.register_refused_steps) p.system.tracker.register_refused_steps = *s.register_refused_steps;
  if (s.start_doubt_s) p.system.tracker.start_doubt_s = *s.start_doubt_s;
  if (s.road_start) p.system.tracker.road_start = *s.road_start;
  if (s.start_by_rays) p.system.tracker.start_by_rays = *s.start_by_rays;
  if (s.confirm_suspect_by_scan) p.system.tracker.confirm_suspect_by_scan = *s.confirm_suspect_by_scan;
  if (s.speed_window_s) p.system.tracker.speed_window_s = *s.speed_window_s;
  if (s.ransac_points_near_prior) {
    p.system.tracker.ransac_max_points_near_prior = static_cast<std::size_t>(*s.ransac_points_near_prior);
  }
  if (s.ransac_points_near_prior_retry) {
    p.system.tracker.ransac_max_points_near_prior_retry = static_cast<std::size_t>(*s.ransac_points_near_prior_retry);
  }
  if (s.depth_consistency) p.system.mapping.depth_consistency = *s.depth_consistency;
  if (s.triangulation) p.system.mapping.triangulation = *s.triangulation;
  if (s.bf || s.th_depth) {
    p.notes.push_back("Camera.bf / ThDepth are not used: rgbl weights depth with an explicit noise model");
  }
}

}  // namespace

void PipelineOptions::validate() const {
  if (dataset.empty()) throw ConfigError("dataset", "a dataset folder");
  if (camera != -1 && camera != 0 && camera != 2) {
    throw ConfigError("camera", fmt::format("0 (grey left), 2 (colour left) or -1 (0 when present), not {}", camera));
  }
  if (step < 1) throw ConfigError("step", "a stride of at least 1 frame");
  if (depth.empty()) throw ConfigError("depth", "a depth source name (lidar, precomputed:<dir>, stereo, ...)");
  if (threads < 0 || threads > 256) {
    throw ConfigError("threads", fmt::format("0 (the machine's hardware threads) or a count from 1 to 256, not {}", threads));
  }
  if (!(playback_rate >= 0.0 && playback_rate <= 1000.0)) {
    throw ConfigError("playback_rate", fmt::format("0 (as fast as tracked) or a rate up to 1000 (1: the recording's own pace), not {}", playback_rate));
  }
}

namespace {
std::unique_ptr<Sequence> open_validated(const PipelineOptions& options) {
  options.validate();
  return open_sequence(options.dataset, options.format);
}
}  // namespace

Pipeline::Pipeline(const PipelineOptions& options, const DepthSourceRegistry& registry)
    : Pipeline(open_validated(options), options, registry) {}

Pipeline::Pipeline(std::unique_ptr<Sequence> sequence, const PipelineOptions& options,
                   const DepthSourceRegistry& registry)
    : options_(options), sequence_(std::move(sequence)), registry_(registry) {
  if (!sequence_) throw ConfigError("sequence", "an opened sequence");
  options_.dataset = sequence_->path();
  options_.format = sequence_->format();
  options_.validate();
  const auto& sensors = sequence_->sensors();
  // The tracker works on grey images: a native grey camera (0) is the default, the colour camera (2)
  // is converted per frame.
  camera_ = options_.camera >= 0 ? options_.camera : (sensors.cameras[0] ? 0 : 2);
  if (!sensors.cameras[static_cast<std::size_t>(camera_)]) {
    throw ConfigError("--camera", fmt::format("a camera the dataset has ({} has no camera {})",
                                              sequence_->path().string(), camera_));
  }
  const KittiCalibration& kitti = sequence_->calibration();
  context_.calibration = kitti.camera(camera_);
  if (sensors.cameras[static_cast<std::size_t>(camera_ + 1)]) {
    context_.stereo_baseline = kitti.baseline(camera_, camera_ + 1);
  }
  if (!options_.settings.empty()) {
    const Settings settings = read_settings(options_.settings);
    RgbdSourceOptions rgbd;
    try {
      apply_settings(settings, {context_.calibration, lidar_, rgbd, system_, orb_, notes_});
    } catch (const ConfigError& e) {
      throw ParseError(settings.file, 0, e.what());  // name the settings file, not just the key
    }
    // the settings file's LiDAR.* keys and DepthMapFactor are the built-ins' starting options
    registry_.add("lidar", lidar_depth_source(lidar_));
    registry_.add("rgbd", rgbd_depth_source(rgbd));
  }
  system_.threaded_mapping = options_.threaded;
  threads_ = options_.threads > 0 ? options_.threads : TaskPool::hardware_threads();
  if (!options_.loop_closing) system_.loop_closing.enabled = false;

  // the dataset must have what the source reads, before any frame is read
  const DepthSourceEntry& entry = registry_.entry(options_.depth);
  depth_name_ = std::string(split_depth_spec(options_.depth).first);
  const std::string& where = sequence_->path().string();
  if (entry.needs.scan && !sensors.lidar) {
    throw ConfigError("--depth", fmt::format("a source the dataset has: {} has no LiDAR scans for '{}' (try stereo or "
                                             "rgbd)", where, depth_name_));
  }
  if (entry.needs.right_image && !sensors.cameras[static_cast<std::size_t>(camera_ + 1)]) {
    throw ConfigError("--depth", fmt::format("{} needs camera {} (image_{}) next to camera {}", depth_name_,
                                             camera_ + 1, camera_ + 1, camera_));
  }
  if (entry.needs.depth_image && !sensors.depth) {
    throw ConfigError("--depth", fmt::format("{} needs depth images: {} has none", depth_name_, where));
  }
  // only what the tracked camera, the depth source and loop closing (the scan's place descriptor) read
  load_.cameras = {};
  load_.cameras[static_cast<std::size_t>(camera_)] = true;
  load_.cameras[static_cast<std::size_t>(camera_ + 1)] = entry.needs.right_image;
  load_.lidar = entry.needs.scan || system_.loop_closing.enabled;
  load_.depth = entry.needs.depth_image;
  const std::size_t size = sequence_->size();
  if (options_.first >= size) {
    throw ConfigError("--first", fmt::format("a frame index below {} (the sequence's length)", size));
  }
  const std::size_t available = (size - options_.first + options_.step - 1) / options_.step;
  count_ = options_.frames == 0 ? available : std::min(options_.frames, available);
  orb_.validate();
  system_.validate();
  // creating the source once validates its options before any frame is read
  (void)make_depth_source();
}

std::unique_ptr<DepthSource> Pipeline::make_depth_source() const { return registry_.create(options_.depth, context_); }

FeatureExtractor Pipeline::make_extractor() const { return make_orb_extractor(orb_); }

ReadAheadOptions Pipeline::read_ahead_options() const {
  ReadAheadOptions read;
  read.first = options_.first;
  read.count = count_;
  read.step = options_.step;
  read.load = load_;
  return read;
}

SensorFrame Pipeline::sensor_frame(const FrameInput& input) const {
  SensorFrame frame;
  frame.index = input.index;
  frame.timestamp = input.timestamp;
  frame.image = input.images[static_cast<std::size_t>(camera_)];
  frame.image_right = input.images[static_cast<std::size_t>(camera_ + 1)];
  frame.depth_image = input.depth;
  frame.scan = input.scan;
  frame.scan_timestamp = input.scan_timestamp;
  return frame;
}

std::unique_ptr<System> Pipeline::make_system() const {
  return std::make_unique<System>(system_, context_.calibration, make_depth_source(), make_extractor());
}

namespace {
// A frame on its way: the loaded input (which the sensor frame views) and its build.
struct InFlight {
  FrameInput input;
  SensorFrame sensor;
  PreparedFrame prepared;
  FrameBuilder* builder = nullptr;  // the pipeline's, which outlive the frames in flight
  bool late_depth = false;          // its scan moved on the tracking thread (System::scan_moves)
  double io_wait_ms = 0.0;
  TaskPool::Task build;  // last: destroyed (waited for) before what it writes to
};

// Holds each frame back until its timestamp, relative to the first frame's, has passed on the wall
// clock (scaled by the rate): the pace of the recording. A stop request ends the wait.
class Pacer {
 public:
  explicit Pacer(double rate) : rate_(rate) {}
  void wait_for(double timestamp, const std::stop_token& stop) {
    if (rate_ <= 0.0 || !std::isfinite(timestamp)) return;
    const auto now = std::chrono::steady_clock::now();
    if (!first_timestamp_) {
      first_timestamp_ = timestamp;
      start_ = now;
      return;
    }
    const auto due = start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>((timestamp - *first_timestamp_) / rate_));
    std::unique_lock lock(mutex_);
    wake_.wait_until(lock, stop, due, [] { return false; });  // only the time or a stop ends it
  }

 private:
  double rate_;
  std::optional<double> first_timestamp_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;  // what wake_ needs to wait on; nothing else is shared
  std::condition_variable_any wake_;
};
}  // namespace

RunResult Pipeline::run(const Progress& progress, std::stop_token stop) const {
  // with frame threads every frame is built by one of the FrameBuilders below, none by the System
  const std::unique_ptr<System> system =
      threads_ > 1 ? std::make_unique<System>(system_, context_.calibration) : make_system();
  ReadAhead frames(*sequence_, read_ahead_options());
  std::vector<FrameRecord> records;
  records.reserve(count_);
  Stopwatch wall;
  Pacer pacer(options_.playback_rate);
  const auto add = [&](FrameRecord record) {
    records.push_back(std::move(record));
    if (progress) progress(records.back(), records.size(), count_);
  };
  if (threads_ <= 1) {
    for (;;) {
      if (stop.stop_requested()) break;
      Stopwatch wait;
      std::optional<FrameInput> input = frames.next();
      const double wait_ms = wait.elapsed_ms();
      if (!input) break;
      FrameRecord record;
      const SensorFrame sensor = sensor_frame(*input);
      pacer.wait_for(sensor.timestamp, stop);
      record.result = system->track(sensor);
      record.io_wait_ms = wait_ms;
      add(std::move(record));
    }
  } else {
    // The next `threads` frames are built on the pool (each one's levels spread over every thread)
    // while frame i is tracked here, so a core is never idle while tracking runs. One builder per
    // frame in flight, as each depth source holds the frame it prepared. A build is a function of
    // its frame alone, except for a scan moved to the image's time by the motion tracked so far
    // (System::scan_moves): that part is finished here, before the builder is reused. The trajectory
    // is the one of a single thread.
    const auto pool = std::make_shared<TaskPool>(threads_);
    system->use_task_pool(pool);
    const auto ahead_max = static_cast<std::size_t>(threads_);
    std::vector<FrameBuilder> builders;
    builders.reserve(ahead_max);
    for (std::size_t b = 0; b < ahead_max; ++b) {
      builders.emplace_back(context_.calibration, system_.depth_noise, make_depth_source(),
                            make_orb_extractor(orb_, pool), pool, system_.tracker.scan_sample);
    }
    std::size_t started = 0;
    bool loaded_all = false;
    std::deque<std::unique_ptr<InFlight>> ahead;
    const auto fill = [&] {  // frame k uses builder k % ahead_max: frame k - ahead_max's build is done
      while (!loaded_all && ahead.size() < ahead_max) {
        Stopwatch wait;
        std::optional<FrameInput> input = frames.next();
        if (!input) {
          loaded_all = true;
          break;
        }
        auto f = std::make_unique<InFlight>();
        f->io_wait_ms = wait.elapsed_ms();
        f->input = std::move(*input);
        f->sensor = sensor_frame(f->input);
        FrameBuilder& builder = builders[started++ % ahead_max];
        f->builder = &builder;
        f->late_depth = !f->sensor.scan.empty() && system->scan_moves(f->sensor);
        f->build = pool->submit([&builder, f = f.get()] {
          f->prepared = f->late_depth ? builder.build_ahead(f->sensor) : builder.build(f->sensor);
        });
        ahead.push_back(std::move(f));
      }
    };
    fill();
    while (!ahead.empty()) {
      if (stop.stop_requested()) break;
      const std::unique_ptr<InFlight> current = std::move(ahead.front());
      ahead.pop_front();
      Stopwatch wait;
      current->build.wait();  // helps with queued builds meanwhile; rethrows what building threw
      current->prepared.critical_ms = wait.elapsed_ms();
      if (current->late_depth) {
        current->sensor.T_image_scan = system->scan_motion(current->sensor);
        current->builder->finish(current->prepared, current->sensor);
      }
      if (!stop.stop_requested()) fill();  // the builds overlap the tracking below
      FrameRecord record;
      pacer.wait_for(current->sensor.timestamp, stop);
      record.result = system->track(current->sensor, std::move(current->prepared));
      record.io_wait_ms = current->io_wait_ms;
      add(std::move(record));
    }
  }
  const bool stopped = stop.stop_requested() && records.size() < count_;
  system->finish();
  RunResult out = collect(*system, std::move(records), wall.elapsed_ms() / 1000.0);
  out.stopped = stopped;
  return out;
}

RunResult Pipeline::collect(System& system, std::vector<FrameRecord> frames, double wall_s) const {
  system.finish();  // no-op when run() has already waited
  RunResult out;
  out.sequence_name = sequence_->name();
  out.sequence_path = sequence_->path();
  out.format = sequence_->format();
  out.camera = camera_;
  out.depth = depth_name_;
  out.first = options_.first;
  out.step = options_.step;
  out.threads = threads_;
  out.threaded = system_.threaded_mapping;
  out.playback_rate = options_.playback_rate;
  out.frames = std::move(frames);
  out.frames_planned = count_;
  out.wall_s = wall_s;
  out.loop_closing = system.loop_closing();
  out.loop_closures = system.loop_closures();  // threaded: some came after the last frame
  out.loop_statistics = system.loop_statistics();

  // Poses of cam0 (KITTI's reference camera) in the world of the ground truth when there is one (so
  // that files line up with poses/NN.txt), else in the first frame's cam0.
  const Eigen::Isometry3d T_cam_cam0 = context_.calibration.T_cam_cam0;
  const auto& gt = sequence_->ground_truth();
  Eigen::Isometry3d T_world_first = Eigen::Isometry3d::Identity();
  if (gt && options_.first < gt->size()) T_world_first = gt->poses[options_.first];
  // the tracker's world is the first tracked camera's frame
  const Eigen::Isometry3d T_out_world = T_world_first * T_cam_cam0.inverse();
  for (const auto& pose : system.trajectory()) {
    out.trajectory.timestamps.push_back(pose.timestamp);
    out.trajectory.poses.push_back(T_out_world * pose.T_world_cam * T_cam_cam0);
  }
  if (gt) {
    for (std::size_t i = 0; i < out.trajectory.poses.size() && frame_index(i) < gt->size(); ++i) {
      out.ground_truth.push_back(gt->poses[frame_index(i)]);
    }
  }
  if (out.ground_truth.size() >= 2) {
    RunMetrics metrics;
    metrics.frames_with_ground_truth = out.ground_truth.size();
    const std::span<const Eigen::Isometry3d> estimate(out.trajectory.poses.data(), out.ground_truth.size());
    metrics.evaluation = evaluate_trajectory(estimate, out.ground_truth);
    std::vector<Eigen::Isometry3d> tracked, tracked_truth;
    for (std::size_t i = 0; i < out.ground_truth.size(); ++i) {
      if (i >= out.frames.size() || !has_pose(out.frames[i].result.state)) continue;
      tracked.push_back(estimate[i]);
      tracked_truth.push_back(out.ground_truth[i]);
    }
    metrics.frames_tracked = tracked.size();
    if (tracked.size() >= 2) metrics.tracked_ate = absolute_trajectory_error(tracked, tracked_truth);
    metrics.kitti_lengths = describe_lengths(metrics.evaluation.kitti_options);
    out.metrics = std::move(metrics);
  }

  // the map, in the same world frame as the trajectory
  const Map& map = system.map();
  std::shared_lock lock(map.mutex());
  for (const auto id : map.landmark_ids()) {
    if (const Landmark* l = map.landmark(id)) out.landmarks.push_back(T_out_world * l->position);
  }
  for (const auto id : map.keyframe_ids()) {
    if (const auto T_cam_world = map.keyframe_pose(id)) {
      out.keyframes.push_back(T_out_world * T_cam_world->inverse() * T_cam_cam0);
    }
  }
  return out;
}

std::size_t RunResult::count(TrackState state) const {
  return static_cast<std::size_t>(
      std::count_if(frames.begin(), frames.end(), [state](const FrameRecord& r) { return r.result.state == state; }));
}

std::size_t RunResult::tracked_count() const {
  return static_cast<std::size_t>(
      std::count_if(frames.begin(), frames.end(), [](const FrameRecord& r) { return has_pose(r.result.state); }));
}

bool RunResult::failed() const { return !stopped && !frames.empty() && tracked_count() == 0; }

std::size_t RunResult::keyframe_count() const {
  return static_cast<std::size_t>(
      std::count_if(frames.begin(), frames.end(), [](const FrameRecord& r) { return r.result.keyframe; }));
}

std::optional<double> RunResult::scan_age_median() const {
  if (frames.empty()) return std::nullopt;
  std::vector<double> ages;
  ages.reserve(frames.size());
  for (const FrameRecord& f : frames) ages.push_back(f.result.scan_age);
  return stage_stats(std::move(ages)).median;
}

std::optional<int> RunResult::min_inliers_ok() const {
  std::optional<int> fewest;
  for (const auto& r : frames) {
    if (r.result.state == TrackState::Ok) fewest = std::min(fewest.value_or(r.result.inliers), r.result.inliers);
  }
  return fewest;
}

StageStats stage_stats(std::vector<double> v) {
  StageStats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) {
    return v[static_cast<std::size_t>(std::min<double>(static_cast<double>(v.size() - 1),
                                                        std::floor(q * static_cast<double>(v.size() - 1) + 0.5)))];
  };
  s.median = at(0.5);
  s.p95 = at(0.95);
  double sum = 0.0;
  for (const double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  s.max = v.back();
  return s;
}

RunTimings RunResult::timings() const {
  const auto stage = [this](auto&& ms) {
    std::vector<double> v;
    v.reserve(frames.size());
    for (const auto& r : frames) v.push_back(ms(r));
    return stage_stats(std::move(v));
  };
  RunTimings t;
  t.io_wait = stage([](const FrameRecord& r) { return r.io_wait_ms; });
  t.depth = stage([](const FrameRecord& r) { return r.result.timing.depth_ms; });
  t.extraction = stage([](const FrameRecord& r) { return r.result.timing.extraction_ms; });
  t.tracking = stage([](const FrameRecord& r) { return r.result.timing.tracking_ms; });
  t.mapping = stage([](const FrameRecord& r) { return r.result.timing.mapping_ms; });
  t.loop = stage([](const FrameRecord& r) { return r.result.timing.loop_ms; });
  t.front = stage([](const FrameRecord& r) { return r.result.timing.front_ms; });
  t.total = stage([](const FrameRecord& r) { return r.result.timing.total_ms; });
  return t;
}

}  // namespace rgbl
