#include "rgbl/tracking/system.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/tracking/local_mapping.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <stdexcept>
#include <thread>

namespace rgbl {

void SystemOptions::validate() const {
  tracker.validate();
  mapping.validate();
  depth_noise.validate();
  map.validate();
  loop_closing.validate();
  require(!scan_time_offset || (std::isfinite(*scan_time_offset) && std::abs(*scan_time_offset) <= kMaxScanAge),
          "scan_time_offset", kScanAgeExpected);
  require(std::isfinite(frame_period) && frame_period > 0.0, "frame_period", "seconds > 0");
}

namespace {
struct FrameRecord {
  std::size_t frame_index = 0;
  double timestamp = 0.0;
  TrackState state = TrackState::NotInitialised;
  KeyframeId reference;
  Eigen::Isometry3d T_cam_reference = Eigen::Isometry3d::Identity();
};

// Jobs for one worker thread, taken one at a time; idle = nothing queued and nothing in hand.
template <class Job>
class WorkQueue {
 public:
  void push(Job job) {
    {
      std::lock_guard lock(mutex_);
      jobs_.push_back(std::move(job));
    }
    wake_.notify_one();
  }
  // The next job (the worker is busy with it until done()), waiting for one; nullopt once stopped,
  // after the queued jobs when `drain`.
  std::optional<Job> pop(bool drain) {
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
    if (stop_ && (!drain || jobs_.empty())) return std::nullopt;
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    busy_ = true;
    return job;
  }
  void done() {
    {
      std::lock_guard lock(mutex_);
      busy_ = false;
    }
    idle_.notify_all();
  }
  bool idle() const {
    std::lock_guard lock(mutex_);
    return !busy_ && jobs_.empty();
  }
  std::size_t queued() const {  // not counting the one in hand
    std::lock_guard lock(mutex_);
    return jobs_.size();
  }
  void wait_idle() {
    std::unique_lock lock(mutex_);
    idle_.wait(lock, [&] { return !busy_ && jobs_.empty(); });
  }
  void stop() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<Job> jobs_;
  bool busy_ = false, stop_ = false;
};

}  // namespace

struct System::Impl {
  SystemOptions options;
  CameraCalibration calibration;
  Map map;
  Tracker tracker;
  LocalMapper mapper;
  LoopCloser closer;
  std::optional<FrameBuilder> builder;  // for track(SensorFrame): the depth source and the extractor
  std::vector<FrameRecord> records;

  std::vector<LoopClosure> closures;  // every closure so far (threaded: guarded by results_mutex)

  // A keyframe on its way through the threads, with its scan for place recognition (the caller's
  // scan does not outlive track()).
  struct KeyframeJob {
    KeyframeId keyframe;
    std::vector<LidarPoint> scan;
    std::vector<LandmarkId> depth_landmarks;  // made with the keyframe (threaded mapping)
    bool initial = false;  // a map's first keyframe: its landmarks only join the culling
  };

  // Threaded mapping, and loop closing (with threaded mapping) fed by it once a keyframe is mapped.
  // Detection runs beside tracking and mapping; a correction holds both gates, so it lands between
  // two frames and between two keyframes of local mapping, never inside one.
  WorkQueue<KeyframeJob> mapping_queue, loop_queue;
  std::thread mapping_thread, loop_thread;
  std::mutex mapping_gate;   // held by the mapping thread per keyframe
  std::mutex tracking_gate;  // held by track() from tracking to the frame's record
  mutable std::mutex results_mutex;  // guards closures, reported, stats while the loop thread runs
  std::size_t reported = 0;          // closures already handed to a TrackResult
  LoopClosingStats stats;            // the loop thread's, after its last keyframe
  // The first exception of a worker thread (guarded by results_mutex); from then on the workers
  // discard their jobs, and the caller's thread rethrows it.
  std::exception_ptr worker_error;

  // Runs a worker's job unless a worker has failed; keeps the first exception.
  template <class F>
  bool run_job(F&& job) {
    {
      std::lock_guard lock(results_mutex);
      if (worker_error) return false;
    }
    try {
      job();
      return true;
    } catch (...) {
      std::lock_guard lock(results_mutex);
      if (!worker_error) worker_error = std::current_exception();
      return false;
    }
  }
  void rethrow_worker_error() const {
    std::exception_ptr error;
    {
      std::lock_guard lock(results_mutex);
      error = worker_error;
    }
    if (error) std::rethrow_exception(error);
  }

  Impl(SystemOptions o, CameraCalibration c, std::unique_ptr<DepthSource> d, FeatureExtractor e)
      : options(o), calibration(c), map(o.map), tracker(map, c.camera, o.tracker, c.T_cam_lidar), mapper(map, c.camera, o.mapping),
        closer(c, o.loop_closing) {
    if (d) builder.emplace(c, o.depth_noise, std::move(d), std::move(e), nullptr, o.tracker.scan_sample);
    if (threaded_loop_closing()) loop_thread = std::thread([this] { run_loop_closing(); });
    if (options.threaded_mapping) mapping_thread = std::thread([this] { run_mapping(); });
  }

  bool threaded_loop_closing() const { return options.threaded_mapping && options.loop_closing.enabled; }

  void run_mapping() {
    // drains the queue when stopped (local mapping aborts its bundle adjustment to be quick)
    while (std::optional<KeyframeJob> next = mapping_queue.pop(/*drain=*/true)) {
      const bool mapped = run_job([&] {
        std::lock_guard gate(mapping_gate);
        if (next->initial) {
          mapper.watch_initial(next->keyframe);
        } else {
          mapper.process(next->keyframe, next->depth_landmarks);
        }
      });
      // before done(): finish() sees it; a first keyframe went to the loop thread from track()
      if (mapped && !next->initial && threaded_loop_closing()) loop_queue.push(std::move(*next));
      mapping_queue.done();
    }
  }

  void run_loop_closing() {
    while (std::optional<KeyframeJob> next = loop_queue.pop(/*drain=*/false)) {
      run_job([&] { close_loops(*next); });
      loop_queue.done();
    }
  }

  // Detection beside tracking and mapping; a correction behind both gates.
  void close_loops(const KeyframeJob& job) {
    std::optional<DetectedLoop> loop;
    LoopCloserStep step = closer.detect(map, job.keyframe, job.scan, loop);
    if (loop) {
      std::scoped_lock gates(mapping_gate, tracking_gate);
      std::optional<Eigen::Isometry3d> T_ref_world_before;
      {
        std::unique_lock lock(map.mutex());
        T_ref_world_before = map.keyframe_pose(tracker.reference_keyframe());
        closer.correct(map, *loop, step);
      }
      // tracking waits at its gate: its last frames follow the reference keyframe here
      if (step.closure && T_ref_world_before) tracker.follow_map_correction(*T_ref_world_before);
    }
    std::lock_guard lock(results_mutex);
    stats = closer.stats();
    if (step.closure) closures.push_back(std::move(*step.closure));
  }

  bool mapping_idle() const { return !options.threaded_mapping || mapping_queue.idle(); }
};

System::System(SystemOptions options, CameraCalibration calibration, std::unique_ptr<DepthSource> depth,
               FeatureExtractor extractor) {
  options.validate();
  calibration.camera.validate();
  if (!depth) throw ConfigError("depth", "a depth source");
  if (!extractor) throw ConfigError("extractor", "a feature extractor");
  impl_ = std::make_unique<Impl>(options, calibration, std::move(depth), std::move(extractor));
}

System::System(SystemOptions options, CameraCalibration calibration) {
  options.validate();
  calibration.camera.validate();
  impl_ = std::make_unique<Impl>(options, calibration, nullptr, FeatureExtractor{});
}

System::~System() {
  if (!impl_) return;
  if (impl_->mapping_thread.joinable()) {  // first: it feeds the loop thread
    impl_->mapping_queue.stop();
    impl_->mapper.request_abort();
    impl_->mapping_thread.join();
  }
  if (impl_->loop_thread.joinable()) {
    impl_->loop_queue.stop();
    impl_->loop_thread.join();
  }
}

void System::add_place_recognizer(std::unique_ptr<PlaceRecognizer> recognizer) {
  // the loop thread reads the recognisers once frames come: no lock, so only before
  if (!impl_->records.empty()) throw std::logic_error("System::add_place_recognizer: only before the first frame");
  impl_->closer.add_place_recognizer(std::move(recognizer));
}

void System::use_task_pool(std::shared_ptr<TaskPool> pool) {
  if (!impl_->records.empty()) throw std::logic_error("System::use_task_pool: only before the first frame");
  impl_->closer.use_task_pool(pool);
  impl_->tracker.use_task_pool(std::move(pool));
}

void System::finish() {
  if (!impl_->options.threaded_mapping) return;
  impl_->mapping_queue.wait_idle();
  impl_->loop_queue.wait_idle();  // mapping has handed over its last keyframe
  impl_->rethrow_worker_error();
}

TrackResult System::track(const SensorFrame& sensor) {
  if (!impl_->builder) {
    throw std::logic_error("System::track(sensor): this System has no depth source and extractor; pass the built frame");
  }
  if (!scan_moves(sensor)) return track(sensor, impl_->builder->build(sensor));
  SensorFrame moved = sensor;
  moved.T_image_scan = scan_motion(sensor);
  return track(sensor, impl_->builder->build(moved));
}

bool System::scan_moves(const SensorFrame& sensor) const { return scan_age(sensor) != 0.0; }

double System::scan_age(const SensorFrame& sensor) const {
  if (impl_->options.scan_time_offset) return *impl_->options.scan_time_offset;
  return sensor.scan_timestamp ? sensor.timestamp - *sensor.scan_timestamp : 0.0;
}

namespace {

// The motion from a scan `age` seconds older than its image to the image, from the tracker's velocity;
// none where that is unknown (no velocity yet, no pose) or the age is 0 or a glitch.
std::optional<Eigen::Isometry3d> known_scan_motion(double age, const Tracker& tracker) {
  const auto& velocity = tracker.velocity();
  const double dt = tracker.velocity_dt();
  // a scan time set by hand (Python) may be a glitch too: no motion rather than a wrong one
  if (age == 0.0 || !(std::abs(age) <= kMaxScanAge) || !has_pose(tracker.state()) || !velocity || !(dt > 0.0)) {
    return std::nullopt;
  }
  return se3_exp(se3_log(*velocity) * (age / dt));
}

}  // namespace

Eigen::Isometry3d System::scan_motion(const SensorFrame& sensor) const {
  return known_scan_motion(scan_age(sensor), impl_->tracker).value_or(Eigen::Isometry3d::Identity());
}

TrackResult System::track(const SensorFrame& sensor, PreparedFrame prepared) {
  Impl& s = *impl_;
  s.rethrow_worker_error();
  TrackResult result;
  result.frame_index = sensor.index;
  result.timestamp = sensor.timestamp;
  Stopwatch total, stage;
  Frame& frame = prepared.frame;
  const std::size_t n = frame.size();
  const int with_depth = prepared.keypoints_with_depth;
  result.timing.extraction_ms = prepared.extraction_ms;
  result.timing.depth_ms = prepared.depth_ms;
  if (!sensor.scan.empty()) {
    result.scan_age = scan_age(sensor);
    // the same test as scan_motion's, on the same tracker state: before this frame is tracked
    frame.scan_at_image_time = result.scan_age == 0.0 || known_scan_motion(result.scan_age, s.tracker).has_value();
  }

  // A loop thread's correction waits for this frame to be tracked and recorded (uncontended inline).
  const std::lock_guard gate(s.tracking_gate);
  const TrackerOutcome outcome =
      s.tracker.track(frame, s.mapping_idle(), s.options.threaded_mapping ? s.mapping_queue.queued() : 0, sensor.scan);
  KeyframeId new_keyframe;
  if (outcome.need_keyframe) new_keyframe = s.tracker.make_keyframe(frame);
  result.timing.tracking_ms = stage.lap_ms();
  result.timing.front_ms = prepared.critical_ms + total.elapsed_ms();

  const auto scan_copy = [&] {
    return s.threaded_loop_closing() ? std::vector<LidarPoint>(sensor.scan.begin(), sensor.scan.end())
                                     : std::vector<LidarPoint>{};
  };
  if (outcome.initialised_now) {
    const KeyframeId first = s.tracker.reference_keyframe();
    if (s.options.threaded_mapping) {
      s.mapping_queue.push({first, {}, {}, true});
    } else {
      s.mapper.watch_initial(first);
    }
  }
  if (new_keyframe.valid()) {
    if (s.options.threaded_mapping) {
      // The keyframe's depth points become landmarks now, on this thread: the next frames track
      // against them even while local mapping lags behind (ORB-SLAM does the same for RGB-D).
      std::vector<LandmarkId> created;
      {
        std::unique_lock lock(s.map.mutex());
        created = create_depth_landmarks(s.map, s.calibration.camera, new_keyframe, s.options.mapping.max_new_depth_points);
      }
      s.mapping_queue.push({new_keyframe, scan_copy(), std::move(created)});
    } else {
      s.mapper.process(new_keyframe);
    }
  }
  result.timing.mapping_ms = stage.lap_ms();

  // The map's first keyframe is a place too (a loop often ends where the drive started).
  const KeyframeId loop_keyframe = outcome.initialised_now ? s.tracker.reference_keyframe() : new_keyframe;
  if (s.threaded_loop_closing()) {
    // the first keyframe is not mapped: straight to the loop thread; the others come from mapping
    if (outcome.initialised_now && loop_keyframe.valid()) s.loop_queue.push({loop_keyframe, scan_copy(), {}});
    std::lock_guard lock(s.results_mutex);
    if (s.reported < s.closures.size()) result.loop_closure = s.closures[s.reported++];
  } else if (loop_keyframe.valid() && s.options.loop_closing.enabled) {
    std::optional<Eigen::Isometry3d> T_ref_world_before;
    {
      std::shared_lock lock(s.map.mutex());
      T_ref_world_before = s.map.keyframe_pose(s.tracker.reference_keyframe());
    }
    LoopCloserStep step = s.closer.process(s.map, loop_keyframe, sensor.scan);
    if (step.closure && T_ref_world_before) {
      // this frame is the reference keyframe: it moves with it, as the tracker's last frames do
      if (const auto moved = s.tracker.follow_map_correction(*T_ref_world_before)) frame.T_cam_world = frame.T_cam_world * *moved;
    }
    if (step.closure) {
      const std::lock_guard lock(s.results_mutex);
      s.closures.push_back(*step.closure);
    }
    result.loop_closure = std::move(step.closure);
  }
  result.timing.loop_ms = stage.lap_ms();

  result.state = outcome.state;
  result.keyframe = outcome.initialised_now || new_keyframe.valid();
  result.relocalised = outcome.relocalised;
  result.new_map = outcome.new_map;
  result.jump = outcome.jump;
  result.step_rejected = outcome.step_rejected;
  result.step_registered = outcome.step_registered;
  result.step_contested = outcome.step_contested;
  result.start_refuted_since = outcome.start_refuted_since;
  result.speed_corrected = outcome.speed_corrected;
  result.start_by_rays = outcome.start_by_rays;
  result.scan_confirmed = outcome.scan_confirmed;
  result.gap = outcome.gap;
  result.gap_registered = outcome.gap_registered;
  result.lost_registered = outcome.lost_registered;
  result.inliers = outcome.inliers;
  result.keypoints = static_cast<int>(n);
  result.keypoints_with_depth = with_depth;
  result.T_world_cam = frame.T_cam_world.inverse();

  FrameRecord record;
  record.frame_index = sensor.index;
  record.timestamp = sensor.timestamp;
  record.state = outcome.state;
  {
    std::shared_lock lock(s.map.mutex());
    record.reference = s.tracker.reference_keyframe();
    result.map_keyframes = s.map.keyframe_count();
    result.map_landmarks = s.map.landmark_count();
    if (const auto T_ref_world = s.map.keyframe_pose(record.reference)) {
      record.T_cam_reference = frame.T_cam_world * T_ref_world->inverse();
    } else {
      record.reference = KeyframeId{};
      record.T_cam_reference = frame.T_cam_world;
    }
  }
  s.records.push_back(record);
  result.timing.total_ms = prepared.critical_ms + total.elapsed_ms();
  return result;
}

std::vector<TrajectoryPose> System::trajectory() const {
  const Impl& s = *impl_;
  std::vector<TrajectoryPose> out;
  out.reserve(s.records.size());
  std::shared_lock lock(s.map.mutex());
  for (const FrameRecord& r : s.records) {
    TrajectoryPose p;
    p.frame_index = r.frame_index;
    p.timestamp = r.timestamp;
    p.state = r.state;
    Eigen::Isometry3d T_cam_world = r.T_cam_reference;
    if (r.reference.valid()) {
      if (const auto T_ref_world = s.map.keyframe_pose(r.reference)) T_cam_world = r.T_cam_reference * *T_ref_world;
    }
    p.T_world_cam = T_cam_world.inverse();
    out.push_back(p);
  }
  return out;
}

const Map& System::map() const { return impl_->map; }
const CameraCalibration& System::calibration() const { return impl_->calibration; }
bool System::loop_closing() const { return impl_->options.loop_closing.enabled; }

LoopClosingStats System::loop_statistics() const {
  if (!impl_->threaded_loop_closing()) return impl_->closer.stats();
  std::lock_guard lock(impl_->results_mutex);
  return impl_->stats;
}

std::vector<LoopClosure> System::loop_closures() const {
  std::lock_guard lock(impl_->results_mutex);  // uncontended inline
  return impl_->closures;
}

}  // namespace rgbl
