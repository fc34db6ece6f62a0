#include "rgbl/tracking/support.hpp"

#include "rgbl/backend/pose_optimizer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rgbl {

const char* to_string(TrackState state) {
  switch (state) {
    case TrackState::NotInitialised: return "not_initialised";
    case TrackState::Ok: return "ok";
    case TrackState::Weak: return "weak";
    case TrackState::Lost: return "lost";
  }
  return "unknown";
}

TrackState support_state(int inliers, std::optional<std::size_t> frames_since_relocalisation,
                         const TrackerOptions& options) {
  const bool after_relocalisation =
      frames_since_relocalisation && *frames_since_relocalisation < static_cast<std::size_t>(options.relocalisation_window);
  const int needed = after_relocalisation ? options.min_ok_inliers_after_relocalisation : options.min_ok_inliers;
  return inliers >= needed ? TrackState::Ok : TrackState::Weak;
}

bool motion_suspect(const MotionEvidence& e, const TrackerOptions& options) {
  const double floor = options.min_pose_inliers;
  const double found_needed = options.verify_min_found_ratio * e.local_visible;
  const double offered = e.last_keypoints > 0
                             ? std::min(1.0, static_cast<double>(e.keypoints) / static_cast<double>(e.last_keypoints))
                             : 1.0;
  const double motion_needed = options.verify_min_motion_ratio * e.last_inliers * offered;
  const bool map_disagrees = found_needed >= floor && e.local_inliers < found_needed;
  const bool motion_collapsed = motion_needed >= floor && e.motion_inliers < motion_needed;
  return map_disagrees || motion_collapsed;
}

bool keyframe_due(const KeyframeEvidence& e, const TrackerOptions& options) {
  const bool need_close =
      e.tracked_close < options.close_tracked_threshold && e.untracked_close > options.close_untracked_threshold;
  const double ratio = e.keyframes < 2 ? options.initial_reference_ratio_threshold : options.reference_ratio_threshold;
  const bool c1a = e.frames_since_keyframe >= options.max_frames_between_keyframes;
  const bool c1c = e.established_inliers < options.urgent_reference_ratio * e.reference_established || need_close;
  const bool thinned = e.inliers < options.reference_landmark_ratio * e.reference_landmarks;
  const bool c2 = (e.established_inliers < ratio * e.reference_established || need_close || thinned) &&
                  e.inliers > options.min_keyframe_inliers;
  return (c1a || e.mapping_idle || c1c) && c2;
}

double allowed_step(double predicted_step_m, double dt, const TrackerOptions& options) {
  const double acceleration_term = dt > 0.0 ? 0.5 * options.max_acceleration * dt * dt : 0.0;
  return options.step_tolerance + options.step_tolerance_relative * std::max(0.0, predicted_step_m) + acceleration_term;
}

StepCheck check_step(const Eigen::Isometry3d& T_cam_world, const Eigen::Isometry3d& T_cam_world_predicted,
                     double predicted_step_m, double dt, const TrackerOptions& options) {
  StepCheck check;
  const Eigen::Vector3d centre = T_cam_world.inverse().translation();
  const Eigen::Vector3d predicted_centre = T_cam_world_predicted.inverse().translation();
  check.translation_m = (centre - predicted_centre).norm();
  const Eigen::AngleAxisd relative(T_cam_world.linear() * T_cam_world_predicted.linear().transpose());
  check.rotation_deg = std::abs(relative.angle()) * 180.0 / std::numbers::pi;
  check.allowed_translation_m = allowed_step(predicted_step_m, dt, options);
  check.translation_plausible = check.translation_m <= check.allowed_translation_m;
  check.plausible = check.translation_plausible && check.rotation_deg <= options.step_tolerance_rotation_deg;
  check.allowed_shortfall_m = check.allowed_translation_m;
  return check;
}

StepCheck check_step(const Eigen::Isometry3d& T_cam_world, const Eigen::Isometry3d& T_cam_world_predicted,
                     const Eigen::Vector3d& last_centre, double dt, const TrackerOptions& options) {
  const Eigen::Vector3d predicted_centre = T_cam_world_predicted.inverse().translation();
  const Eigen::Vector3d step = predicted_centre - last_centre;
  const double s = step.norm();
  StepCheck check = check_step(T_cam_world, T_cam_world_predicted, s, dt, options);
  const double reach = dt > 0.0 ? options.max_acceleration * dt * dt : 0.0;  // a dt^2
  if (!(s > 0.0) || !(s < reach)) return check;  // the isotropic bound is the braking bound
  check.shortfall_m = s - (T_cam_world.inverse().translation() - last_centre).dot(step / s);
  const double braking = s - s * s / (2.0 * reach);
  check.allowed_shortfall_m = options.step_tolerance + options.step_tolerance_relative * s + braking;
  if (check.shortfall_m > check.allowed_shortfall_m) {
    check.translation_plausible = false;
    check.plausible = false;
  }
  return check;
}

std::optional<SpeedCheck> check_speed(std::span<const PlacedCentre> recent, double time, const Eigen::Vector3d& centre,
                                      const TrackerOptions& options) {
  const double window = options.speed_window_s;
  if (!(window > 0.0) || recent.size() < 3) return std::nullopt;
  const double reach = 0.9 * window;
  // the latest entry at least `reach` before t, searched from the newest back
  const auto latest_before = [&](std::size_t end, double t) -> std::optional<std::size_t> {
    for (std::size_t i = end; i-- > 0;) {
      if (t - recent[i].time >= reach) return i;
    }
    return std::nullopt;
  };
  const auto anchor = latest_before(recent.size(), time);
  if (!anchor || *anchor + 1 >= recent.size()) return std::nullopt;
  const auto start = latest_before(*anchor, recent[*anchor].time);
  if (!start) return std::nullopt;
  const PlacedCentre& a = recent[*anchor];
  const PlacedCentre& b = recent[*start];
  SpeedCheck check;
  check.velocity = (a.centre - b.centre) / (a.time - b.time);
  check.span_s = time - a.time;
  check.frames_back = recent.size() - *anchor;
  check.expected_centre = a.centre + check.velocity * check.span_s;
  check.deviation_m = (centre - check.expected_centre).norm();
  check.allowed_m = allowed_step(check.velocity.norm() * check.span_s, check.span_s, options);
  check.plausible = check.reaches(centre);
  return check;
}

void TravelDirection::add(const Eigen::Isometry3d& T_last_world, const Eigen::Isometry3d& T_cur_world,
                          const TrackerOptions& options) {
  const Eigen::Vector3d step = step_in_mid_frame(T_last_world, T_cur_world);
  const double length = step.norm();
  if (!(length >= options.direction_min_step_m)) return;
  Eigen::Vector3d u = step / length;
  if (seen_m_ > 0.0 && u.dot(mean_) < 0.0) u = -u;
  const double w = std::min(1.0, length);
  // the mean of every step seen: the mount does not move, and a running mean over the last metres
  // would learn the tracker's own passing errors back into the prior
  const double rate = w / (seen_m_ + w);
  mean_ = (mean_ + rate * (u - mean_)).normalized();
  seen_m_ += w;
}

std::optional<Eigen::Vector3d> TravelDirection::direction(const TrackerOptions& options) const {
  if (seen_m_ < options.direction_learned_m) return std::nullopt;
  return mean_;
}

}  // namespace rgbl
