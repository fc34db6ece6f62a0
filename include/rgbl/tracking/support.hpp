#pragma once
// The rules that say how far a tracked frame's pose can be trusted and when it becomes a keyframe, as
// pure functions so that each is stated once and unit-tested on its own.
//
// A frame is `ok` only with enough support: ORB-SLAM's thresholds, min_ok_inliers (30) map-point
// inliers, and min_ok_inliers_after_relocalisation (50) for relocalisation_window frames after a
// relocalisation, when the pose has no motion history to back it. A frame with a pose but less
// support is `weak`. Independently, a step is plausible only if it stays within what a vehicle can do
// between two frames (StepBounds); an implausible step is taken only on the evidence a relocalisation
// needs, and then reported as a jump, never silently.

#include "rgbl/tracking/options.hpp"

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <span>

namespace rgbl {

enum class TrackState { NotInitialised, Ok, Weak, Lost };

const char* to_string(TrackState state);

// A pose was estimated for the frame (ok or weak).
constexpr bool has_pose(TrackState state) { return state == TrackState::Ok || state == TrackState::Weak; }

// `ok` or `weak` for a frame tracked with `inliers` map-point inliers; frames_since_relocalisation is
// empty when there was none (0 = this frame was relocalised).
TrackState support_state(int inliers, std::optional<std::size_t> frames_since_relocalisation,
                         const TrackerOptions& options);

// What the keyframe decision looks at, counted on the frame just tracked.
struct KeyframeEvidence {
  int keyframes = 0;              // in the map
  int frames_since_keyframe = 0;
  bool mapping_idle = false;
  int reference_established = 0;  // the reference keyframe's landmarks seen by enough keyframes
  int reference_landmarks = 0;    // all of the reference keyframe's landmarks still in the map
  int inliers = 0;                // the frame's inliers on landmarks...
  int established_inliers = 0;    // ...and those on landmarks seen by enough keyframes
  int tracked_close = 0, untracked_close = 0;  // keypoints with depth under close_depth
};

// ORB-SLAM3's RGB-D keyframe rule (SPEC 5) counted like with like: a keyframe is due when the frame
// tracks fewer than reference_ratio_threshold (initial_reference_ratio_threshold while the map has
// one keyframe) of the reference keyframe's established landmarks, counting only its own inliers on
// established landmarks, or needs close points, or tracks fewer than reference_landmark_ratio of all
// the reference's landmarks (young ones too); and max_frames_between_keyframes have passed,
// mapping is idle or it is urgent (urgent_reference_ratio); never on min_keyframe_inliers inliers or
// fewer.
bool keyframe_due(const KeyframeEvidence& e, const TrackerOptions& options);

// What the check of the motion-model hypothesis looks at (TrackerOptions::verify_min_found_ratio and
// verify_min_motion_ratio).
struct MotionEvidence {
  int motion_inliers = 0;             // inliers the motion model kept
  int last_inliers = 0;               // the last frame's, 0 when it was not tracked
  std::size_t keypoints = 0;          // the frame's
  std::size_t last_keypoints = 0;     // the last frame's
  int local_inliers = 0;              // local-map points the search re-found...
  int local_visible = 0;              // ...of those predicted visible
};

// The motion-model pose disagrees with the map (the local-map search re-finds fewer than
// verify_min_found_ratio of the points predicted visible) or with the recent frames (it keeps fewer
// than verify_min_motion_ratio of the last frame's inliers, scaled by the share of the last frame's
// keypoint count this frame has where that is below 1: a frame on plain surfaces, where the extractor
// finds fewer, can keep only as many fewer at the right pose; a wrong pose leaves the count as it is).
// Each check judges only where passing it means at least min_pose_inliers points: a thinner local map
// or last frame is mapping lagging behind or the weak-tracking fallback, and says nothing of the pose.
bool motion_suspect(const MotionEvidence& e, const TrackerOptions& options);

// How far (m) a camera centre may end up from the constant-velocity prediction of a step of
// predicted_step_m over dt seconds: step_tolerance + step_tolerance_relative * step + max_acceleration
// * dt^2 / 2 (dt <= 0: unknown, the acceleration term left out).
double allowed_step(double predicted_step_m, double dt, const TrackerOptions& options);

// How far a pose is from the constant-velocity prediction, and whether that is within a vehicle's
// reach in dt seconds.
struct StepCheck {
  double translation_m = 0.0;    // distance between the two camera centres
  double rotation_deg = 0.0;     // angle of the relative rotation
  double allowed_translation_m = 0.0;
  // How far the centre fell short of the predicted step along it, and how far braking can explain
  // (the overload with the last centre; 0 and the isotropic bound otherwise).
  double shortfall_m = 0.0;
  double allowed_shortfall_m = 0.0;
  bool translation_plausible = true;  // the centre within reach (the rotation may still be off)
  bool plausible = true;
};

// T_cam_world poses; predicted_step_m is the length of the predicted step (its relative tolerance),
// dt the time since the previous frame (its acceleration tolerance; <= 0: unknown, not counted).
StepCheck check_step(const Eigen::Isometry3d& T_cam_world, const Eigen::Isometry3d& T_cam_world_predicted,
                     double predicted_step_m, double dt, const TrackerOptions& options);

// The same, the predicted step running from the last centre (world frame), and a vehicle does not
// reverse: braking at max_acceleration from the speed s / dt, it still covers s^2 / (2 a dt^2) when it
// stops within dt (s < a dt^2), so it falls short of the predicted step by at most s - s^2 / (2 a dt^2)
// there, less than the isotropic a dt^2 / 2. Only after a gap or a slow frame rate does that bind (at
// 10 Hz and 1 g it takes a step under 0.1 m): a frame placed where the car was before a 2 s gap,
// 23.6 m short at 11 m/s, is not within reach, though 23.6 m is within a dt^2 / 2 = 22 m + tolerance.
StepCheck check_step(const Eigen::Isometry3d& T_cam_world, const Eigen::Isometry3d& T_cam_world_predicted,
                     const Eigen::Vector3d& last_centre, double dt, const TrackerOptions& options);

// A camera centre at a time: the recent tracked frames that check_speed reads, oldest first.
struct PlacedCentre {
  double time = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // world frame
};

// Where the speed before a window puts a frame, and whether the frame is within a vehicle's reach of
// that. check_step bounds each step against the last one, so a run of steps each within its tolerance
// can still change the speed faster than a vehicle can (a map pulled onto trucks at the ego speed
// gives 0.76, 0.41, 0.20 m for true 1.0 m steps). Here the anchor is speed_window_s back: the mean
// velocity over the window before the anchor, carried from the anchor to the frame's time.
struct SpeedCheck {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // m/s, world frame, over the window before the anchor
  Eigen::Vector3d expected_centre = Eigen::Vector3d::Zero();
  double span_s = 0.0;       // from the anchor to the frame
  std::size_t frames_back = 0;  // the anchor is this many entries before the frame
  double deviation_m = 0.0;  // of the centre from expected_centre
  double allowed_m = 0.0;    // allowed_step over the span
  bool plausible = true;     // reaches(the centre checked)
  // Another centre at the same time within the vehicle's reach of expected_centre.
  bool reaches(const Eigen::Vector3d& centre) const { return (centre - expected_centre).norm() <= allowed_m; }
};

// recent: consecutive tracked frames, oldest first, the last one the frame before `time`. The anchor is
// the latest entry at least speed_window_s before `time` (90 %: timestamps jitter), the window before it
// ends at the latest entry as far before the anchor. Empty when speed_window_s is 0, when the history is
// too short or when the anchor is the last frame (check_step covers one frame's step).
std::optional<SpeedCheck> check_speed(std::span<const PlacedCentre> recent, double time, const Eigen::Vector3d& centre,
                                      const TrackerOptions& options);

// The car's direction of travel in the camera's frame (the mount's yaw and pitch against the car's
// axis), learned from tracked steps long enough to give a direction: each step in the camera frame
// turned half-way through it (step_in_mid_frame), weighted by its length up to 1 m, into the mean of
// all unit vectors seen (reversing counts as the same line). It is the direction of the tracker's motion prior
// (TrackerOptions::direction_prior) once steps of direction_learned_m in all have been seen.
class TravelDirection {
 public:
  void add(const Eigen::Isometry3d& T_last_world, const Eigen::Isometry3d& T_cur_world, const TrackerOptions& options);
  std::optional<Eigen::Vector3d> direction(const TrackerOptions& options) const;

 private:
  Eigen::Vector3d mean_ = Eigen::Vector3d::UnitZ();
  double seen_m_ = 0.0;
};

}  // namespace rgbl
