#pragma once
// What `rgbl run` does, as a library: open a dataset, choose the depth source and options, track every
// frame, re-express the poses in the ground truth's world, evaluate, and write every output.
//
//   rgbl::PipelineOptions options;
//   options.dataset = "sequences/04";
//   const rgbl::Pipeline pipeline(options);
//   const rgbl::RunResult result = pipeline.run();
//   rgbl::write_run_outputs(result, "out");  // trajectory_kitti.txt, summary.json, ...

#include "rgbl/depth/sources.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/io/read_ahead.hpp"
#include "rgbl/io/sequence.hpp"
#include "rgbl/io/trajectory_io.hpp"
#include "rgbl/tracking/system.hpp"

#include <Eigen/Geometry>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

namespace rgbl {

class OutputFolder;

struct PipelineOptions {
  std::filesystem::path dataset;  // KITTI odometry sequences/NN, KITTI raw drive or TUM RGB-D folder
  DatasetFormat format = DatasetFormat::automatic;
  int camera = -1;          // tracked camera, 0 or 2; -1: 0 when the dataset has it, else 2
  std::size_t first = 0;    // first frame
  std::size_t frames = 0;   // frames to process; 0 = all
  std::size_t step = 1;     // every step-th frame (2: KITTI at 5 Hz)
  // Depth source: name[:argument] of the registry, e.g. lidar, lidar:diamond7, precomputed:<dir>, stereo.
  std::string depth = "lidar";
  std::filesystem::path settings;  // ORB-SLAM style settings YAML (RGB-L's LiDAR.* keys too); empty: defaults
  bool threaded = false;           // local mapping and loop closing in threads of their own
  bool loop_closing = true;        // false overrides the settings file
  // Threads for a frame's own work: with 2 or more, the next frame is built (depth, extraction, the
  // pyramid levels on every thread) while this one is tracked. 0 = the machine's hardware threads.
  // The trajectory is the same for every count.
  int threads = 0;
  // Frames fed at their timestamps' pace times this rate (1: as recorded, as in the car; 0: as fast as
  // they are tracked). Offline, frames come faster than in the car, so threaded mapping is left behind
  // more than it would be there; paced, it has a frame's real time to keep up. No effect on
  // inline runs' trajectories (only on their wall time).
  double playback_rate = 0.0;

  // Throws ConfigError naming the option (dataset, camera, step, threads, playback_rate).
  void validate() const;
};

// One tracked frame and how long the tracker waited for it to be loaded.
struct FrameRecord {
  TrackResult result;
  double io_wait_ms = 0.0;
};

struct StageStats {
  double median = 0.0, p95 = 0.0, mean = 0.0, max = 0.0;  // ms; 0 for no samples
};
StageStats stage_stats(std::vector<double> samples_ms);

// Per-frame timing of every stage over a run.
struct RunTimings {
  StageStats io_wait, depth, extraction, tracking, mapping, loop;
  StageStats front;  // depth + extraction + tracking: what a frame waits for before its pose
  StageStats total;
};

// Accuracy against the ground truth over the frames it covers. A frame that was not tracked (lost or
// not initialised) still has a pose in the trajectory, a guess (extrapolated, or the start): evaluation
// covers every frame, tracked_ate the tracked ones only (aligned on them).
struct RunMetrics {
  std::size_t frames_with_ground_truth = 0;
  std::size_t frames_tracked = 0;  // of those, tracked (ok or weak)
  TrajectoryEvaluation evaluation;  // all frames with ground truth
  std::optional<AteResult> tracked_ate;  // the tracked frames alone, when at least 2 were
  std::string kitti_lengths;  // describe_lengths() of the lengths used
};

// Everything a run produced, in the ground truth's world frame: poses are T_world_cam0 of KITTI's
// reference camera (so trajectory files line up with poses/NN.txt) whatever the tracked camera; with
// no ground truth the world is the first frame's cam0.
struct RunResult {
  // what ran
  std::string sequence_name;
  std::filesystem::path sequence_path;
  DatasetFormat format = DatasetFormat::automatic;
  int camera = 0;
  std::string depth;  // the depth source's registry name
  std::size_t first = 0, step = 1;
  int threads = 1;  // frame threads (PipelineOptions::threads, resolved)
  bool threaded = false;
  double playback_rate = 0.0;  // PipelineOptions::playback_rate
  bool loop_closing = false;

  std::vector<FrameRecord> frames;
  std::size_t frames_planned = 0;  // what the run was to track; more than frames.size() when stopped
  bool stopped = false;            // stopped on request before the last frame: every output is partial
  Trajectory trajectory;                        // a pose per frame, corrected by every loop closure
  std::vector<Eigen::Isometry3d> ground_truth;  // rows of `trajectory` that have ground truth (from the first)
  std::vector<LoopClosure> loop_closures;
  LoopClosingStats loop_statistics;
  std::vector<Eigen::Vector3d> landmarks;     // the final map
  std::vector<Eigen::Isometry3d> keyframes;   // T_world_cam0 of every keyframe
  double wall_s = 0.0;
  std::optional<RunMetrics> metrics;          // with >= 2 frames of ground truth

  std::size_t count(TrackState state) const;
  std::size_t tracked_count() const;  // frames with a tracked pose (ok or weak)
  // A whole run that tracked no frame: its trajectory is guesses, no result (write_run_outputs writes
  // no trajectory for it). A stopped run is partial, not failed.
  bool failed() const;
  std::size_t keyframe_count() const;
  std::optional<int> min_inliers_ok() const;  // fewest local-map inliers on a frame reported ok
  // s, the median over the frames of the time their LiDAR depth was moved by (TrackResult::scan_age)
  std::optional<double> scan_age_median() const;
  RunTimings timings() const;
  // Dataset indices of the frames whose TrackResult satisfies `selected`, e.g. [](auto& r) { return r.jump; }.
  template <typename Selected>
  std::vector<std::size_t> frames_where(Selected&& selected) const {
    std::vector<std::size_t> indices;
    for (const auto& r : frames) {
      if (selected(r.result)) indices.push_back(r.result.frame_index);
    }
    return indices;
  }
};

// A dataset opened and every option resolved and validated: construction fails early, naming the
// option, file or key that is wrong, before any frame is tracked.
class Pipeline {
 public:
  // Throws rgbl::Error (ConfigError, ParseError). `registry` resolves options.depth; a settings file
  // replaces its lidar and rgbd entries with built-ins starting from the file's options.
  explicit Pipeline(const PipelineOptions& options, const DepthSourceRegistry& registry = builtin_depth_sources());
  // A sequence opened by the caller (e.g. make_synthetic_sequence: the simulator, rendered as it is
  // loaded); options.dataset and options.format are then the sequence's own.
  Pipeline(std::unique_ptr<Sequence> sequence, const PipelineOptions& options,
           const DepthSourceRegistry& registry = builtin_depth_sources());

  const PipelineOptions& options() const { return options_; }
  const Sequence& sequence() const { return *sequence_; }
  int camera() const { return camera_; }
  const CameraCalibration& calibration() const { return context_.calibration; }
  const DepthSourceContext& depth_context() const { return context_; }
  const std::string& depth_name() const { return depth_name_; }  // the registry name of options().depth
  const LidarSourceOptions& lidar_options() const { return lidar_; }  // the settings file's (defaults without one)
  const SystemOptions& system_options() const { return system_; }
  const OrbOptions& orb_options() const { return orb_; }
  std::size_t frame_count() const { return count_; }   // frames run() tracks
  std::size_t frame_index(std::size_t i) const { return options_.first + i * options_.step; }
  // The frames run() tracks, loaded ahead on a second thread: only the images, scan and depth image
  // that the tracked camera, the depth source and loop closing read.
  ReadAheadOptions read_ahead_options() const;
  // Decisions taken on the user's behalf (e.g. "LiDAR.Tr overrides the dataset's extrinsics"), to show once.
  const std::vector<std::string>& notes() const { return notes_; }

  std::unique_ptr<DepthSource> make_depth_source() const;
  FeatureExtractor make_extractor() const;
  int threads() const { return threads_; }  // options().threads resolved (0: the hardware threads)
  // The depth source's view of one loaded frame of the tracked camera (images shared, not copied).
  SensorFrame sensor_frame(const FrameInput& input) const;

  // Called after every frame with the frames done so far; a place for progress output.
  using Progress = std::function<void(const FrameRecord& record, std::size_t done, std::size_t total)>;
  // Tracks every frame (the next ones loaded on a second thread), waits for threaded mapping and loop
  // closing, and evaluates. Throws what loading a frame throws (ParseError naming the file).
  // A stop requested on `stop` (from the progress callback, another thread, a signal's watcher) ends
  // the run before the next frame: the result then holds what was tracked, with stopped set.
  RunResult run(const Progress& progress = {}, std::stop_token stop = {}) const;

  // run() in parts, for a caller that feeds the frames itself (the Python module): the System run()
  // tracks with, and the RunResult of the frames it tracked (after system.finish()), re-expressed in
  // the ground truth's world and evaluated exactly as run() does. `frames` are the records of frames
  // frame_index(0), frame_index(1), ... in order.
  std::unique_ptr<System> make_system() const;
  RunResult collect(System& system, std::vector<FrameRecord> frames, double wall_s = 0.0) const;

 private:
  PipelineOptions options_;
  std::unique_ptr<Sequence> sequence_;
  DepthSourceRegistry registry_;
  int camera_ = 0;
  DepthSourceContext context_;
  std::string depth_name_;
  LidarSourceOptions lidar_;
  SystemOptions system_;
  OrbOptions orb_;
  std::size_t count_ = 0;
  int threads_ = 1;
  LoadOptions load_;
  std::vector<std::string> notes_;
};

// The files write_run_outputs() writes.
const std::vector<std::string>& run_output_files();

// Removes an earlier run's outputs from `out_dir` (an output left over from it would look like this
// run's if this one fails), and the temporaries (<name>.<random>.part) of a run killed while writing
// them. Call it holding the folder (OutputFolder).
void remove_run_outputs(const std::filesystem::path& out_dir);

// Writes into `out_dir` (created, and locked against other processes while writing: OutputFolder):
// trajectory_kitti.txt, trajectory_tum.txt, ground_truth_kitti.txt (with ground truth; row for row
// with trajectory_kitti.txt), timing.csv (a row per frame, a column per stage), summary.json,
// trajectory.svg (with the ground truth and the loop closures) and map.ply (landmarks and keyframes).
// Each file is written whole and renamed into place (write_atomically). A stopped run's summary.json
// says "partial": true. A failed() run gets timing.csv and summary.json alone, which say why; an
// earlier run's trajectory files must be gone first (remove_run_outputs).
void write_run_outputs(const RunResult& result, const std::filesystem::path& out_dir);
// The same into a folder the caller holds (taken before the run, so that an unusable or busy folder is
// found before tracking).
void write_run_outputs(const RunResult& result, const OutputFolder& out_dir);

// summary.json's content.
std::string summary_json(const RunResult& result);

// The run in a few lines for people, as `rgbl run` prints it: frame states, keyframes, jumps, new maps,
// loop closures, per-stage medians and p95s, and the accuracy when there is ground truth.
std::string summary_text(const RunResult& result);

}  // namespace rgbl
