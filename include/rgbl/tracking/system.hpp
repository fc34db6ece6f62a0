#pragma once
// The facade: one call per frame from sensor data to a pose. Owns the map, the tracker, local mapping
// (inline, deterministic, or in its own thread), the depth source and the feature extractor.

#include "rgbl/backend/depth_noise.hpp"
#include "rgbl/depth/depth_source.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/loop/loop_closer.hpp"
#include "rgbl/map/map.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/frame_builder.hpp"
#include "rgbl/tracking/options.hpp"
#include "rgbl/tracking/tracker.hpp"

#include <Eigen/Geometry>

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

namespace rgbl {

struct SystemOptions {
  TrackerOptions tracker;
  LocalMappingOptions mapping;
  DepthNoiseModel depth_noise;
  MapOptions map;
  // Loop closing after local mapping on every keyframe.
  LoopClosingOptions loop_closing;
  // false: local mapping and loop closing run inside track() and the same input gives a bit-identical
  // trajectory. true: local mapping in a thread of its own, and loop closing in another.
  bool threaded_mapping = false;
  // LiDAR depth moved to the image's time (SensorFrame::T_image_scan) with the constant-velocity
  // estimate: a LiDAR that triggers the camera still measures before the exposure (KITTI raw: 16.9 ms,
  // 17 cm at 10 m/s). scan_time_offset: the image's time minus the scan's, for every frame; unset =
  // the dataset's scan timestamps (SensorFrame::scan_timestamp; KITTI raw has them), else 0
  // (simultaneous, nothing moved).
  std::optional<double> scan_time_offset;  // s, |.| <= 1
  double frame_period = 0.1;       // s between frames given without a timestamp (Python's System.track)

  void validate() const;
};

// Milliseconds spent per stage on one frame. mapping_ms is the inline local-mapping time (0 when
// mapping runs in its own thread). With more than one thread, stages overlap (the depth source's
// preparation beside extraction, the next frame's extraction beside this frame's tracking): each
// stage's figure is its own duration, front_ms and total_ms what the frame cost the tracking thread.
struct StageTiming {
  double depth_ms = 0.0;       // prepare + keypoint sampling
  double extraction_ms = 0.0;
  double tracking_ms = 0.0;
  double mapping_ms = 0.0;
  double loop_ms = 0.0;  // loop detection, verification and correction (keyframes only)
  double front_ms = 0.0;  // wall, from the frame's turn to its pose (depth, extraction, tracking)
  double total_ms = 0.0;  // wall, from the frame's turn to the next frame's
};

struct TrackResult {
  std::size_t frame_index = 0;
  double timestamp = 0.0;
  TrackState state = TrackState::NotInitialised;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // world = first tracked camera pose
  bool keyframe = false;
  bool relocalised = false;  // placed by relocalisation against the whole map
  bool new_map = false;      // tracking was lost and a new map started here (poses anchored at a guess)
  bool jump = false;         // a step beyond a vehicle's reach, taken on strong evidence
  bool step_rejected = false;  // a step beyond a vehicle's reach on weak evidence: weak, at the prediction
  bool step_registered = false;  // ...placed by its scan's registration onto the last frame's instead
  // a step beyond a vehicle's reach refused although clearly more inliers (two sigmas) agree with it
  // than with the pose kept: weak
  bool step_contested = false;
  // a contested step taken within TrackerOptions::start_doubt_s of a start without velocity: the start
  // was wrong, and the frames from this one (its index) up to this frame were placed on it
  std::optional<std::size_t> start_refuted_since;
  // the speed had changed faster than a vehicle can over TrackerOptions::speed_window_s, and the
  // keypoints without depth took a pose within reach of the speed before (ok unless contested too)
  bool speed_corrected = false;
  // a start without velocity chosen by the keypoints without depth against the road and the inliers
  // (TrackerOptions::start_by_rays; its scale unchecked until a contested step)
  bool start_by_rays = false;
  // a suspect motion-model pose kept, not lost, because the frame's scan registered onto the last one
  // near it (TrackerOptions::confirm_suspect_by_scan)
  bool scan_confirmed = false;
  // the first frame after a gap in the timestamps, its scan registered onto the last frame's
  // (TrackerOptions::register_gaps); gap_registered: the registration was accepted as the prediction
  bool gap = false;
  bool gap_registered = false;
  // a lost frame placed by its scan's registration onto the last frame's (TrackerOptions::register_lost)
  bool lost_registered = false;
  int inliers = 0;           // local-map inliers (ok needs 30, 50 after a relocalisation)
  int keypoints = 0, keypoints_with_depth = 0;
  // s, the image's time minus its scan's, by which the LiDAR depth was moved (System::scan_age; 0 without)
  double scan_age = 0.0;
  std::size_t map_keyframes = 0, map_landmarks = 0;  // the map's size after this frame
  // A loop closed: inline, on this frame (a keyframe); threaded, by the loop thread since the last
  // frame (its frame_index says which keyframe closed it). The map was corrected.
  std::optional<LoopClosure> loop_closure;
  StageTiming timing;
};

struct TrajectoryPose {
  std::size_t frame_index = 0;
  double timestamp = 0.0;
  TrackState state = TrackState::NotInitialised;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

class System {
 public:
  System(SystemOptions options, CameraCalibration calibration, std::unique_ptr<DepthSource> depth,
         FeatureExtractor extractor);
  // Without a depth source and an extractor of its own: every frame comes built (track(sensor, prepared),
  // e.g. by FrameBuilders on other threads); track(sensor) throws std::logic_error.
  System(SystemOptions options, CameraCalibration calibration);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // Adds a place recogniser of your own to loop closing (see LoopCloser::add_place_recognizer).
  // Before the first frame: std::logic_error after it.
  void add_place_recognizer(std::unique_ptr<PlaceRecognizer> recognizer);

  // Tracking's work that splits (the scans' registration across a gap in the frames) runs on
  // `pool`, e.g. the one that builds the frames; the trajectory is the same with any pool or none.
  // Before the first frame: std::logic_error after it.
  void use_task_pool(std::shared_ptr<TaskPool> pool);

  // Throws what the depth source throws on unusable input (e.g. no right image for the stereo
  // source); a frame without depth (e.g. a dropped LiDAR scan) is tracked on the map alone. With
  // threaded mapping, an exception thrown in the mapping or loop-closing thread (e.g. by a recogniser
  // of your own) stops that thread's work and is rethrown here, at the next frame, or by finish().
  TrackResult track(const SensorFrame& frame);
  // The same with the frame built beforehand (e.g. on another thread, by a FrameBuilder of its own):
  // `sensor` is the frame it was built from, still needed for its scan (loop closing).
  // A LiDAR frame's depth is the image's only when built from a sensor frame with T_image_scan =
  // scan_motion(sensor), taken after the previous frame was tracked (FrameBuilder::build_ahead, finish).
  TrackResult track(const SensorFrame& sensor, PreparedFrame prepared);

  // The camera's motion from the frame's scan to its image (SensorFrame::T_image_scan), from the
  // constant-velocity estimate of the frames tracked so far: identity before two tracked frames,
  // while lost, or when the two are simultaneous. Depends on the tracking state: take it for the
  // next frame, after the previous one was tracked.
  Eigen::Isometry3d scan_motion(const SensorFrame& sensor) const;
  // Whether scan_motion can be other than the identity for this frame (scan_age != 0): then its
  // depth is built after the previous frame was tracked.
  bool scan_moves(const SensorFrame& sensor) const;
  // The image's time minus the scan's (SystemOptions::scan_time_offset, else the frame's own times).
  double scan_age(const SensorFrame& sensor) const;

  // Waits until threaded mapping and loop closing have processed every queued keyframe (no-op when
  // inline); the trajectory then includes every correction. Rethrows a worker thread's exception.
  void finish();

  // Every frame so far, with poses refined by mapping (frames are stored relative to their reference
  // keyframe, as ORB-SLAM does).
  std::vector<TrajectoryPose> trajectory() const;

  // Lock map().mutex() (shared) to read while threaded mapping runs.
  const Map& map() const;
  const CameraCalibration& calibration() const;
  // Loops are closed (inline, or with threaded mapping in a thread of its own).
  bool loop_closing() const;
  // What the loop closer considered so far (all zero without loop closing).
  LoopClosingStats loop_statistics() const;
  // Every closure so far, in order. In a thread of its own a closure is also reported in the
  // TrackResult of the first frame tracked after it; after finish() this holds them all.
  std::vector<LoopClosure> loop_closures() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbl
