#include "rgbl/tracking/frame.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/tracking/options.hpp"

#include <algorithm>
#include <memory>
#include <cmath>

namespace rgbl {

FeatureExtractor make_orb_extractor(const OrbOptions& options, std::shared_ptr<TaskPool> pool) {
  auto extractor = std::make_shared<OrbExtractor>(options);
  return [extractor, pool](const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors) {
    extractor->extract(gray, keypoints, descriptors, pool.get());
  };
}


void TrackerOptions::validate() const {
  scan_sample.validate();
  object_residuals.validate();
  require(std::isfinite(gap_interval_ratio) && gap_interval_ratio > 1.0, "tracker.gap_interval_ratio",
          "> 1 (times the last frame interval)");
  require(std::isfinite(max_gap_s) && max_gap_s > 0.0, "tracker.max_gap_s", "> 0 s");
  require(std::isfinite(gap_tolerance_m) && gap_tolerance_m > 0.0, "tracker.gap_tolerance_m", "> 0 m");
  require(std::isfinite(gap_tolerance_deg) && gap_tolerance_deg > 0.0, "tracker.gap_tolerance_deg", "> 0 deg");
  gap_registration.validate();
  require(std::isfinite(lidar_start_max_speed) && lidar_start_max_speed >= 0.0, "tracker.lidar_start_max_speed",
          ">= 0 m/s (0 = off)");
  direction_prior_sigmas.validate();
  require(std::isfinite(direction_min_step_m) && direction_min_step_m > 0.0, "tracker.direction_min_step_m", "> 0 m");
  require(std::isfinite(direction_learned_m) && direction_learned_m >= 0.0, "tracker.direction_learned_m", ">= 0 m");
  require(min_initial_depth_points >= 10, "tracker.min_initial_depth_points", ">= 10");
  require(motion_radius > 0.0, "tracker.motion_radius", "> 0");
  require(local_map_radius > 0.0, "tracker.local_map_radius", "> 0");
  require(max_hamming > 0 && max_hamming <= 256, "tracker.max_hamming", "in (0, 256]");
  require(motion_max_hamming > 0 && motion_max_hamming <= 256, "tracker.motion_max_hamming", "in (0, 256]");
  require(ransac_max_hamming > 0 && ransac_max_hamming <= 256, "tracker.ransac_max_hamming", "in (0, 256]");
  require(local_map_ratio > 0.0 && local_map_ratio <= 1.0, "tracker.local_map_ratio", "in (0, 1]");
  require(reference_ratio > 0.0 && reference_ratio <= 1.0, "tracker.reference_ratio", "in (0, 1]");
  require(reference_min_matches >= 3, "tracker.reference_min_matches", ">= 3 (a pose needs 3 points)");
  require(max_local_keyframes >= 1, "tracker.max_local_keyframes", ">= 1");
  require(min_pose_inliers >= 3, "tracker.min_pose_inliers", ">= 3");
  require(verify_min_found_ratio >= 0.0 && verify_min_found_ratio <= 1.0, "tracker.verify_min_found_ratio",
          "in [0, 1]");
  require(verify_min_motion_ratio >= 0.0 && verify_min_motion_ratio <= 1.0, "tracker.verify_min_motion_ratio",
          "in [0, 1]");
  require(relocalisation_min_found_ratio >= 0.0 && relocalisation_min_found_ratio <= 1.0,
          "tracker.relocalisation_min_found_ratio", "in [0, 1]");
  require(relocalisation_min_matches >= 6, "tracker.relocalisation_min_matches", ">= 6 (PnP RANSAC)");
  require(relocalisation_ratio > 0.0 && relocalisation_ratio <= 1.0, "tracker.relocalisation_ratio", "in (0, 1]");
  require(relocalisation_ransac_iterations >= 1, "tracker.relocalisation_ransac_iterations", ">= 1");
  require(relocalisation_ransac_px > 0.0, "tracker.relocalisation_ransac_px", "> 0 px");
  require(relocalisation_ransac_confidence > 0.0 && relocalisation_ransac_confidence < 1.0,
          "tracker.relocalisation_ransac_confidence", "in (0, 1)");
  require(ransac_iterations >= 1, "tracker.ransac_iterations", ">= 1");
  require(ransac_max_points >= 3 && ransac_max_points_near_prior >= 3, "tracker.ransac_max_points",
          ">= 3 keypoints (a rigid motion needs 3 points), with a prior and without");
  require(ransac_min_inliers >= 3, "tracker.ransac_min_inliers", ">= 3 (a rigid motion needs 3 points)");
  require(ransac_guess_min_inliers >= 3, "tracker.ransac_guess_min_inliers", ">= 3 (a rigid motion needs 3 points)");
  require(ransac_coverage_cell >= 0.0, "tracker.ransac_coverage_cell", ">= 0 px (0 = rank by size only)");
  require(ransac_prior_translation >= 0.0, "tracker.ransac_prior_translation", ">= 0 m");
  require(ransac_prior_relative >= 0.0, "tracker.ransac_prior_relative", ">= 0");
  require(ransac_prior_rotation_deg >= 0.0 && ransac_prior_rotation_deg <= 180.0, "tracker.ransac_prior_rotation_deg",
          "in [0, 180] degrees");
  require(motion_gate_factor >= 0.0, "tracker.motion_gate_factor", ">= 0 (0 = off)");
  require(moving_label_radius >= 0.0, "tracker.moving_label_radius", ">= 0 px (0 = seeds only)");
  require(ground_min_height >= 0.0, "tracker.ground_min_height", ">= 0 m");
  require(ground_max_tilt_deg >= 0.0 && ground_max_tilt_deg < 90.0, "tracker.ground_max_tilt_deg", "in [0, 90) degrees");
  require(ground_tolerance > 0.0, "tracker.ground_tolerance", "> 0 m");
  require(ground_min_points >= 3, "tracker.ground_min_points", ">= 3 (a plane needs 3 points)");
  require(ground_iterations >= 1, "tracker.ground_iterations", ">= 1");
  require(min_ok_inliers >= min_pose_inliers, "tracker.min_ok_inliers", ">= tracker.min_pose_inliers");
  require(min_ok_inliers_after_relocalisation >= min_ok_inliers, "tracker.min_ok_inliers_after_relocalisation",
          ">= tracker.min_ok_inliers");
  require(relocalisation_window >= 0, "tracker.relocalisation_window", ">= 0 frames");
  require(step_tolerance >= 0.0, "tracker.step_tolerance", ">= 0 m");
  require(step_tolerance_relative >= 0.0, "tracker.step_tolerance_relative", ">= 0");
  require(max_acceleration >= 0.0, "tracker.max_acceleration", ">= 0 m/s^2");
  require(step_tolerance_rotation_deg >= 0.0 && step_tolerance_rotation_deg <= 180.0,
          "tracker.step_tolerance_rotation_deg", "in [0, 180] degrees");
  require(min_jump_inliers >= min_pose_inliers, "tracker.min_jump_inliers", ">= tracker.min_pose_inliers");
  require(start_doubt_s >= 0.0 && std::isfinite(start_doubt_s), "tracker.start_doubt_s", ">= 0 s (0 = off)");
  require(speed_window_s >= 0.0 && std::isfinite(speed_window_s), "tracker.speed_window_s", ">= 0 s (0 = off)");
  require(max_frames_between_keyframes >= 1, "tracker.max_frames_between_keyframes", ">= 1");
  require(max_queued_keyframes >= 1, "tracker.max_queued_keyframes", ">= 1");
  require(reference_ratio_threshold > 0.0 && reference_ratio_threshold <= 1.0, "tracker.reference_ratio_threshold",
          "in (0, 1]");
  require(initial_reference_ratio_threshold > 0.0 && initial_reference_ratio_threshold <= 1.0,
          "tracker.initial_reference_ratio_threshold", "in (0, 1]");
  require(urgent_reference_ratio >= 0.0 && urgent_reference_ratio <= 1.0, "tracker.urgent_reference_ratio",
          "in [0, 1] (0 = off)");
  require(reference_landmark_ratio >= 0.0 && reference_landmark_ratio <= 1.0, "tracker.reference_landmark_ratio",
          "in [0, 1] (0 = off)");
  require(close_depth > 0.0, "tracker.close_depth", "> 0");
  pose.validate();
}

void LocalMappingOptions::validate() const {
  require(max_new_depth_points >= 0, "local_mapping.max_new_depth_points", ">= 0");
  require(max_local_ba_keyframes >= 1, "local_mapping.max_local_ba_keyframes", ">= 1");
  pairs.validate();
  require(min_found_ratio >= 0.0 && min_found_ratio <= 1.0, "local_mapping.min_found_ratio", "in [0, 1]");
  require(redundant_ratio > 0.0 && redundant_ratio <= 1.0, "local_mapping.redundant_ratio", "in (0, 1]");
  require(place_distance_ratio > 0.0 && place_distance_ratio < 1.0, "local_mapping.place_distance_ratio",
          "a fraction of the median depth in (0, 1)");
  require(place_angle_deg > 0.0 && place_angle_deg < 90.0, "local_mapping.place_angle_deg", "in (0, 90) degrees");
  require(revisit_path_ratio >= 1.0, "local_mapping.revisit_path_ratio", ">= 1");
  require(max_keyframes_per_place >= 2, "local_mapping.max_keyframes_per_place",
          ">= 2 (the place's first keyframe and the new one)");
  fusion_match.validate();
  triangulation_match.validate();
  require(triangulation_min_views >= 2, "local_mapping.triangulation_min_views", ">= 2 (the two views it was made from)");
  ba.validate();
  lidar_registration.validate();
  require(lidar_min_probe_loss >= 0.0 && lidar_min_probe_loss < 1.0, "local_mapping.lidar_min_probe_loss", "in [0, 1)");
  require(lidar_max_change_m > 0.0, "local_mapping.lidar_max_change_m", "> 0 m");
  require(lidar_max_change_deg > 0.0, "local_mapping.lidar_max_change_deg", "> 0 deg");
}

}  // namespace rgbl
