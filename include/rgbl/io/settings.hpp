#pragma once
// Settings files in ORB-SLAM's style (`%YAML:1.0`, read with OpenCV's FileStorage), including the
// RGB-L reference's keys, mapped onto plain values. Every key is optional, but groups are all or
// nothing: Camera.fx/fy/cx/cy, and LiDAR.Tr11..LiDAR.Tr34. Unknown keys are kept as warnings.
//
// Keys read (ORB-SLAM3's `Camera1.` prefix is accepted for the camera too):
//   Camera.fx fy cx cy [k1 k2 p1 p2 k3] [width height], Camera.fps, Camera.bf, Camera.RGB,
//   ThDepth, DepthMapFactor,
//   ORBextractor.nFeatures scaleFactor nLevels iniThFAST minThFAST,
//   LiDAR.Method, LiDAR.min_dist, LiDAR.max_dist, LiDAR.Tr11 .. LiDAR.Tr34 (T_cam_lidar, row-major),
//   LiDAR.MethodInverseDilation.KernelType, LiDAR.MethodInverseDilation.KernelSize_u,
//   rgbl's own LiDAR.OcclusionWindowDeg (0 = off), LiDAR.OcclusionRatio (LidarSourceOptions::occlusion_*),
//   LiDAR.SurfaceFitWindowDeg (LidarSourceOptions::surface_fit_window_deg, 0 = off, default 0.5),
//   LiDAR.SurfaceStepPx (LidarSourceOptions::surface_step_px, 1 .. 15, default 2),
//   LiDAR.KernelFromRingSpacing (0/1, LidarSourceOptions::kernel_from_ring_spacing, default 1),
//   LiDAR.RegistrationSigmaDeg (DepthNoiseModel::registration_sigma_deg, 0 = off, default 0.1),
//   LiDAR.TimeOffset (SystemOptions::scan_time_offset: the image's time minus the scan's, seconds;
//   overrides the dataset's scan timestamps, 0 = simultaneous),
//   LiDAR.ElevationCorrection (ScanSampleOptions::elevation_correction_deg, -2 .. 2 deg, default 0: every
//   return of the scan samples turned up by it, e.g. KITTI's HDL-64 0.205; not the depth),
//   rgbl's own Tracking.ReferenceLandmarkRatio (TrackerOptions::reference_landmark_ratio, 0..1) and
//   Tracking.BoundedDepthError (0/1, PoseOptimizerOptions::bounded_depth_error of the tracker),
//   Tracking.CauchyWeights (0/1, PoseOptimizerOptions::cauchy of the tracker: Cauchy weights after a
//   Huber round, default 1),
//   Tracking.ObjectTest (0/1, TrackerOptions::object_test: objects whose residuals err together left out),
//   Tracking.DirectionPrior (0/1, TrackerOptions::direction_prior: the step held across the car's
//   direction of travel, default 1),
//   Tracking.RegisterGaps (0/1, TrackerOptions::register_gaps: the scans registered across a gap),
//   Tracking.RegisterLost (0/1, TrackerOptions::register_lost: a lost frame placed by its scan),
//   Tracking.RegisterRefusedSteps (0/1, TrackerOptions::register_refused_steps: a frame whose step was
//   refused placed by its scan, default 1),
//   Tracking.StartDoubt (TrackerOptions::start_doubt_s: seconds after a start without velocity in which
//   a contested step is taken when the keypoints without depth favour it, default 1, 0 = off),
//   Tracking.RoadStart (0/1, TrackerOptions::road_start: a start without velocity proposed by the road's
//   keypoints alone, default 1),
//   Tracking.ConfirmSuspectByScan (0/1, TrackerOptions::confirm_suspect_by_scan: a suspect motion-model
//   pose kept when the frame's scan registers onto the last one close to it, default 1),
//   Tracking.StartByRays (0/1, TrackerOptions::start_by_rays: two starts decided by the keypoints
//   without depth where they clearly favour one, before the LiDAR, default 1),
//   Tracking.SpeedWindow (TrackerOptions::speed_window_s: seconds over which the speed may not change
//   faster than a vehicle's, the keypoints without depth deciding where it did, default 0.3, 0 = off),
//   Tracking.RansacPointsNearPrior (TrackerOptions::ransac_max_points_near_prior: keypoints with depth in
//   the frame-to-frame RANSAC near a constant-velocity prior, default 350; 1000 takes every one),
//   Tracking.RansacPointsNearPriorRetry (TrackerOptions::ransac_max_points_near_prior_retry: keypoints
//   with depth in a second RANSAC near the prior when the first finds too few, default 0 = none; 1000 opt-in),
//   LocalMapping.DepthConsistency (0/1, LocalMappingOptions::depth_consistency: a landmark's depth
//   sigmas scaled by how far its depths disagree with its keyframes' parallax),
//   LocalMapping.Triangulation (0/1, LocalMappingOptions::triangulation: landmarks triangulated between
//   keyframes for keypoints without depth),
//   rgbl's own LoopClosing.Enabled (0/1), MaxPlaceDistance, ConsistentKeyframes, MaxDriftPercent,
//   MaxDriftDegPer100m, Fuse (0/1), GlobalBA (0/1), MergeMaps (0/1) (LoopClosingOptions' fields of those
//   names), LoopClosing.Scans (0/1, LoopScanOptions::enabled: the loop measured again by the scans), LocalMapping.PlaceCulling (0/1), LocalMapping.LidarPairSigma (m, 0 = off, default 0.02:
//   KeyframePairOptions::lidar_sigma_translation, keyframes tied by their scans' registration),
//   LocalMapping.LidarPairSigmaRotation (rad: that pair's lidar_sigma_rotation),
//   LocalMapping.LidarPairAgreeingSigma (m, 0 = as LidarPairSigma: lidar_agreeing_sigma_translation).
// Viewer.* and other display-only ORB-SLAM keys are accepted and ignored without a warning.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/projection.hpp"

#include <Eigen/Geometry>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace rgbl {

struct OrbSettings {
  int n_features = 2000;
  double scale_factor = 1.2;
  int n_levels = 8;
  int ini_th_fast = 12;  // absent keys keep OrbOptions' defaults (SPEC 5), not ORB-SLAM's 20
  int min_th_fast = 7;
  // rgbl's own key ORBextractor.featuresPerNode (OrbOptions::features_per_node); unset = the default.
  std::optional<int> features_per_node;
  // rgbl's own key ORBextractor.spreadFraction (OrbOptions::spread_fraction); unset = the default.
  std::optional<double> spread_fraction;

  void validate() const;
};

// rgbl's LoopClosing.* keys; unset = LoopClosingOptions' default.
struct LoopClosingSettings {
  std::optional<bool> enabled;
  std::optional<double> max_place_distance;
  std::optional<std::vector<std::string>> places;  // LoopClosing.Places: "scan_context,bow"
  std::optional<std::filesystem::path> vocabulary;  // LoopClosing.Vocabulary, relative to the settings file
  std::optional<int> consistent_keyframes;
  std::optional<double> max_drift_percent;
  std::optional<double> max_drift_deg_per_100m;
  std::optional<bool> fuse;
  std::optional<bool> global_ba;
  std::optional<bool> merge_maps;
  std::optional<bool> scans;              // LoopClosing.Scans (0/1)
  std::optional<bool> bridge;             // LoopClosing.BridgeGaps (0/1)
  std::optional<double> bridge_max_gap_s;  // LoopClosing.BridgeMaxGap, seconds

  void validate() const;  // ConfigError naming the LoopClosing.* key
};

struct Settings {
  std::filesystem::path file;
  std::optional<PinholeCamera> camera;  // width/height 0 when the file does not give them
  std::optional<double> fps;
  std::optional<double> bf;        // stereo baseline times fx, pixels*m
  std::optional<bool> rgb_order;   // Camera.RGB: 1 = RGB, 0 = BGR
  std::optional<double> th_depth;  // close/far threshold, in baselines
  std::optional<double> depth_map_factor;
  OrbSettings orb;
  std::string lidar_method;      // e.g. "InverseDilation"; empty when absent
  ProjectionOptions projection;  // LiDAR.min_dist, LiDAR.max_dist
  std::optional<Eigen::Isometry3d> T_cam_lidar;
  std::string kernel_type;            // e.g. "Diamond"; empty when absent
  int kernel_size = 0;                // 0 when absent
  std::optional<bool> kernel_from_ring_spacing;  // LiDAR.KernelFromRingSpacing; unset = the source's default (on)
  std::optional<double> occlusion_window_deg;  // LiDAR.OcclusionWindowDeg; unset = the source's default
  std::optional<double> occlusion_ratio;       // LiDAR.OcclusionRatio; unset = the source's default
  std::optional<double> surface_fit_window_deg;  // LiDAR.SurfaceFitWindowDeg; unset = the source's default (0.5)
  std::optional<int> surface_step_px;            // LiDAR.SurfaceStepPx; unset = the source's default (2)
  std::optional<double> registration_sigma_deg;  // LiDAR.RegistrationSigmaDeg; unset = the model's default
  // LiDAR.ElevationCorrection: ScanSampleOptions::elevation_correction_deg (deg; the scan samples only)
  std::optional<double> elevation_correction_deg;
  std::optional<double> scan_time_offset;      // LiDAR.TimeOffset, s; unset = the dataset's scan timestamps
  LoopClosingSettings loop_closing;
  std::optional<bool> place_culling;  // LocalMapping.PlaceCulling: keyframe culling by revisits
  // LocalMapping.LidarPairSigma: KeyframePairOptions::lidar_sigma_translation (m, 0 = off)
  std::optional<double> lidar_pair_sigma;
  // LocalMapping.LidarPairSigmaRotation: KeyframePairOptions::lidar_sigma_rotation (rad, > 0)
  std::optional<double> lidar_pair_sigma_rotation;
  // LocalMapping.LidarPairAgreeingSigma: KeyframePairOptions::lidar_agreeing_sigma_translation (m)
  std::optional<double> lidar_pair_agreeing_sigma;
  std::optional<double> reference_landmark_ratio;  // Tracking.ReferenceLandmarkRatio
  std::optional<bool> bounded_depth_error;          // Tracking.BoundedDepthError
  std::optional<bool> cauchy_weights;               // Tracking.CauchyWeights
  std::optional<bool> object_test;                  // Tracking.ObjectTest
  std::optional<bool> direction_prior;              // Tracking.DirectionPrior
  std::optional<bool> register_gaps;                // Tracking.RegisterGaps
  std::optional<bool> register_lost;                // Tracking.RegisterLost
  std::optional<bool> register_refused_steps;       // Tracking.RegisterRefusedSteps
  std::optional<double> start_doubt_s;              // Tracking.StartDoubt
  std::optional<bool> road_start;                   // Tracking.RoadStart
  std::optional<bool> start_by_rays;                // Tracking.StartByRays
  std::optional<bool> confirm_suspect_by_scan;      // Tracking.ConfirmSuspectByScan
  std::optional<double> speed_window_s;             // Tracking.SpeedWindow
  std::optional<int> ransac_points_near_prior;      // Tracking.RansacPointsNearPrior
  std::optional<int> ransac_points_near_prior_retry;  // Tracking.RansacPointsNearPriorRetry
  std::optional<bool> depth_consistency;            // LocalMapping.DepthConsistency
  std::optional<bool> triangulation;                // LocalMapping.Triangulation
  std::vector<std::string> warnings;  // unknown keys, one message each
};

// Throws ParseError naming the file (and the key) when the file cannot be read, is not a FileStorage
// YAML, a value has the wrong type, a group is incomplete or a value is out of range.
Settings read_settings(const std::filesystem::path& yaml);

}  // namespace rgbl
