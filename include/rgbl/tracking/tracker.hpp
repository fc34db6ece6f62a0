#pragma once
// The tracking state machine: not initialised -> ok <-> lost. Each frame is matched against the map
// (motion model, reference-keyframe fallback, local map, relocalisation) and its pose optimised; a
// suspect motion-model pose is checked by relocalisation, and a camera lost where the map cannot place
// it starts a new map. The tracker also decides when a frame becomes a keyframe. It never throws on bad
// input: failure is a state.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/options.hpp"
#include "rgbl/tracking/support.hpp"

#include <optional>

namespace rgbl {

struct TrackerOutcome {
  TrackState state = TrackState::NotInitialised;
  bool initialised_now = false;
  bool relocalised = false;
  bool new_map = false;         // lost, relocalisation failed: a new map was started at this frame
  bool need_keyframe = false;
  int inliers = 0;
  // The pose's step from the previous frame exceeded what a vehicle can do (see check_step):
  bool jump = false;           // ...taken on strong evidence (min_jump_inliers) and reported
  bool step_rejected = false;  // ...on weak evidence: the frame is weak, placed at the prediction
};

class Tracker {
 public:
  Tracker(Map& map, const PinholeCamera& camera, TrackerOptions options);

  // Tracks the frame (sets frame.T_cam_world, landmarks, outliers). When initialised_now or
  // need_keyframe, the caller turns the frame into a keyframe with make_keyframe().
  TrackerOutcome track(Frame& frame, bool mapping_idle);

  // Adds the frame as a keyframe to the map (taking the map lock) and makes it the reference.
  KeyframeId make_keyframe(const Frame& frame);

  // The map was corrected (a loop closed): the reference keyframe, which was at T_ref_world_before,
  // moved, and the last frames move with it so that the next prediction lands on the corrected map.
  // Returns that move as D (a frame's T_cam_world becomes T_cam_world * D); nullopt without a reference.
  std::optional<Eigen::Isometry3d> follow_map_correction(const Eigen::Isometry3d& T_ref_world_before);

  TrackState state() const { return state_; }
  KeyframeId reference_keyframe() const { return reference_; }
  // Constant-velocity motion T_cur_last of the last tracked frame pair, if any.
  const std::optional<Eigen::Isometry3d>& velocity() const { return velocity_; }

 private:
  struct LocalMapResult {
    bool ok = false;
    int inliers = 0;
    int visible = 0;  // local-map points predicted in view (searched for)
  };

  bool initialise(Frame& frame, const Eigen::Isometry3d& T_cam_world);
  // Returns the pose inliers (landmarks and temporary points), 0 when matching failed.
  // Guided matching against `reference` (the last frame, or after a loss the last tracked one) from
  // T_guess, refined by the frame-to-frame motion from depth (constrained to `prior` if given).
  int track_with_motion_model(Frame& frame, const Frame& reference, const Eigen::Isometry3d& T_guess,
                              const std::optional<Eigen::Isometry3d>& prior);
  // The velocity as a motion prior: only while it comes from two consecutive tracked frames.
  std::optional<Eigen::Isometry3d> trusted_velocity() const {
    return options_.ransac_motion_prior && velocity_steady_ ? velocity_ : std::nullopt;
  }
  bool track_reference_keyframe(Frame& frame);
  // Unmatches keypoints labelled moving and those whose landmark disagrees with frame.T_cam_world (a
  // depth-consensus prediction; see disagrees_with_pose).
  void drop_moving_matches(Frame& frame, double slack = 0.0) const;
  // Keypoint i against world point p_world seen from frame.T_cam_world: in 3-D where it has depth
  // (beyond slack metres more than the gate), else beyond the guided-matching radius in the image.
  bool disagrees_with_pose(const Frame& frame, std::size_t i, const Eigen::Vector3d& p_world, double slack = 0.0) const;
  LocalMapResult track_local_map(Frame& frame);
  // The motion-model hypothesis disagrees with the map or with the recent frames (see TrackerOptions).
  bool suspect(int motion_inliers, const LocalMapResult& local) const;
  bool relocalise(Frame& frame);
  // The local-map search from a relocalised pose re-finds enough of the points it predicts visible.
  bool relocalisation_confirmed(const LocalMapResult& local) const;
  // extra: (keypoint, world point) correspondences that are not landmarks (temporary points).
  int optimise_pose(Frame& frame, const std::vector<std::pair<std::size_t, Eigen::Vector3d>>& extra = {});
  bool need_keyframe(const Frame& frame, int inliers, bool mapping_idle) const;
  std::optional<std::size_t> frames_since_relocalisation(const Frame& frame) const {
    if (last_relocalisation_frame_ == 0 || frame.index < last_relocalisation_frame_) return std::nullopt;
    return frame.index - last_relocalisation_frame_;
  }
  void update_local_map(const Frame& frame);

  Map& map_;
  PinholeCamera camera_;
  TrackerOptions options_;
  TrackState state_ = TrackState::NotInitialised;
  KeyframeId reference_;
  std::size_t last_keyframe_frame_ = 0;
  std::size_t last_relocalisation_frame_ = 0;
  std::size_t last_ok_frame_ = 0;
  int last_inliers_ = 0;  // of the last frame if it was tracked, else 0
  std::optional<Frame> last_frame_;
  std::optional<Frame> last_tracked_frame_;  // while lost: the last frame that was tracked
  std::optional<Eigen::Isometry3d> velocity_;  // T_cur_last
  double velocity_dt_ = 0.0;  // timestamp difference of that pair (0 = unknown)
  bool velocity_steady_ = false;  // velocity_ comes from two consecutive tracked frames (no relocalisation)
  std::vector<KeyframeId> local_keyframes_;
  std::vector<LandmarkId> local_landmarks_;
};

}  // namespace rgbl
