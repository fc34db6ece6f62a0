#pragma once
// Every threshold of tracking and local mapping, with ORB-SLAM3's RGB-D values as defaults where the
// SPEC gives them.

#include "rgbl/backend/bundle_adjustment.hpp"
#include "rgbl/backend/depth_noise.hpp"
#include "rgbl/backend/map_bundle.hpp"
#include "rgbl/backend/pose_optimizer.hpp"
#include "rgbl/tracking/object_residuals.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/map/fusion.hpp"
#include "rgbl/map/triangulation.hpp"
#include "rgbl/map/map.hpp"

namespace rgbl {

struct TrackerOptions {
  // Keypoints with usable depth to initialise. ORB-SLAM starts a depth camera's map from any frame of
  // more than 500 keypoints; 300 with depth (the first value here) never started on KITTI 04 with a
  // 16-ring LiDAR (every fourth ring: 144-281 keypoints with depth a frame; docs/accuracy.md, "Sparser
  // LiDARs"). 100 keeps three times the support an ok frame needs (min_ok_inliers).
  int min_initial_depth_points = 100;
  double motion_radius = 15.0;          // px at level 0, guided matching with the motion model
  int motion_min_matches = 20;          // retry with 2x radius below this
  int motion_max_hamming = 100;
  double motion_ratio = 1.0;            // best/second-best test on the same level (1 = off, as ORB-SLAM)
  double local_map_radius = 3.0;        // px at level 0, local-map search
  int max_hamming = 100;
  double local_map_ratio = 0.8;
  double reference_ratio = 0.7;         // brute-force fallback against the reference keyframe
  int reference_min_matches = 15;       // ...and the matches it needs to try a pose (ORB-SLAM's 15)
  double min_view_cos = 0.5;            // viewing-angle test
  int max_local_keyframes = 80;
  int min_pose_inliers = 10;            // pose optimisation success
  // Relocalisation: brute-force matches against every landmark with ORB-SLAM's ratio, then PnP RANSAC
  // (EPnP) on them with ORB-SLAM's iterations and confidence (it stops early once that sure).
  double relocalisation_ratio = 0.75;
  int relocalisation_ransac_iterations = 300;
  double relocalisation_ransac_px = 4.0;  // inlier reprojection error
  double relocalisation_ransac_confidence = 0.99;
  int relocalisation_min_matches = 15;  // map-wide descriptor matches to try a relocalisation (PnP RANSAC)
  // ...and the share of the local-map points predicted visible that the search re-finds (judged where
  // that means at least min_pose_inliers points). On KITTI 04's repetitive road wrong relocalisations
  // (7.9 and 29 m off) re-found 9.3-9.4 %, right ones >= 16.6 %.
  double relocalisation_min_found_ratio = 0.12;
  // local map fails but the motion model held: keep going as a `weak` frame (and add a keyframe)
  bool keep_weak_tracking = true;
  std::size_t recent_loss_frames = 5;   // after a loss, try the motion model this long before relocalising
  // Verification of the motion-model hypothesis (a jump in the input lands on a repetitive road that
  // the map "explains" from a pose tens of metres off). It is suspect when the local-map search re-finds
  // fewer than verify_min_found_ratio of the local-map points predicted visible, or the motion model
  // keeps fewer than verify_min_motion_ratio of the last frame's inliers, scaled down by the share of
  // its keypoint count the frame has where that is smaller (0 = that check off). Each
  // judges only where passing means at least min_pose_inliers points (a thinner local map or last
  // frame is mapping lagging behind, as in threaded mode, and says nothing about the pose). A suspect
  // frame is relocalised against the whole map and the hypothesis with more local-map inliers is kept;
  // if relocalisation fails, the frame is lost.
  double verify_min_found_ratio = 0.05;
  double verify_min_motion_ratio = 0.2;
  // Right after a tracked frame, a suspect hypothesis that relocalisation could not replace is not
  // lost when the frame's scan registers onto the last one (register_lost's registration and checks)
  // and the pose is within a step's tolerance of the registration, or the local map searched from
  // the registration ends there on an ok frame's support. A truck passing close hides most of a map it
  // has not changed and pulls the motion model; the scans see the car among the facades around it
  // (traffic seed 71, standing: 62 of 1686 points in view re-found, the motion model 0.78 m off;
  // from the registration the local map re-finds 110).
  bool confirm_suspect_by_scan = true;
  // Lost for longer than recent_loss_frames and relocalisation failed: start a new map (disconnected
  // keyframes in the same Map, anchored at the constant-velocity guess) instead of staying lost.
  bool new_map_when_lost = true;
  bool check_orientation = true;        // rotation histogram consistency in guided matching
  // Depth gate in guided matching (0 sigmas = off): |measured - predicted z| <= max(min, sigmas * sigma).
  double depth_gate_sigmas = 3.0;
  double depth_gate_min_motion = 1.0;     // m, around the constant-velocity prediction
  double depth_gate_min_local_map = 0.3;  // m, around the motion-model pose
  // Prediction from depth-to-depth RANSAC between consecutive frames instead of constant velocity
  bool ransac_prediction = true;
  int ransac_max_hamming = 64;
  double ransac_ratio = 0.7;
  int ransac_iterations = 100;
  // Current keypoints with depth used (a strided subset beyond this), without a motion prior and with
  // one. With a prior only motions near it can win, so more keypoints add support: where vehicles hide
  // most of the scene, a subset of 350 left 13-27 static matches, short of ransac_min_inliers, and no
  // prediction (simulator traffic seed 7: 0.088 -> 0.047 m with 1000). Over the whole table 1000 near
  // the prior gains 2 % on the stress scenarios but raw_extended goes 0.0888 -> 0.0900 m and suburban
  // seed 9 0.026 -> 0.036 m, so it is not the default (docs/accuracy.md, "Every keypoint with depth
  // near the prior"). Without a prior, more matches are more chances for a consensus that is not the
  // scene's: with every keypoint, KITTI 04 at every 6th frame ran off by 19 m in two of five samples.
  std::size_t ransac_max_points = 350;
  std::size_t ransac_max_points_near_prior = 350;
  // With a prior and fewer than ransac_min_inliers near it on that subset, the RANSAC is run again on
  // up to this many (0 = never): only the frames that lack the evidence pay for more. With 1000:
  // traffic seed 7 0.088 -> 0.047 m, as with 1000 on every frame, and the rest of the simulator's
  // table and the real drives at 10 Hz barely move; but KITTI 04 at 5 Hz retries on half its frames
  // and gets worse in 9 of 10 samples (0.032 -> 0.039 m), through the moving labels the retry sets.
  // So it is opt-in (docs/accuracy.md, "A second RANSAC near the prior").
  std::size_t ransac_max_points_near_prior_retry = 0;
  int ransac_min_inliers = 30;
  int ransac_guess_min_inliers = 12;       // as the start of tracking against the reference keyframe
  double ransac_min_tolerance = 0.2;       // m
  double ransac_relative_tolerance = 0.03; // of z
  // Consensus is ranked by the number of ransac_coverage_cell-pixel image cells its points occupy,
  // then by its size (0 = size only): a compact object moving with the camera can hold more matches
  // than the static scene, but the scene covers more of the image.
  double ransac_coverage_cell = 64.0;
  // Motion prior on that prediction: a vehicle cannot change its velocity much between frames, so
  // while the velocity comes from two consecutive tracked frames only rigid motions close to constant
  // velocity are considered (translation within ransac_prior_translation + ransac_prior_relative *
  // |step|, rotation within ransac_prior_rotation_deg); the best of them refines the prediction, and
  // with fewer than ransac_min_inliers the constant-velocity prediction stands. Without it a rigid
  // object moving with the camera (a van ahead at the same speed) whose corners outnumber the static
  // scene's takes over the pose. A real jump in the input is left to the verification below.
  bool ransac_motion_prior = true;
  // The road does not move: consensus is ranked by the coverage cells of its points on the ground
  // plane first (a plane at least ground_min_height below the camera, normal within
  // ground_max_tilt_deg of the camera's vertical, ground_min_points of the current frame's depth
  // points within max(ground_tolerance, ransac_relative_tolerance * z)); without such a plane, by
  // coverage alone. A truck alongside at the ego speed may fill half the image, never the road.
  bool ransac_ground_first = true;
  // Once that consensus predicts the pose, a keypoint whose landmark lies further than
  // motion_gate_factor RANSAC tolerances from its measured 3-D point is not used for the pose: it is on
  // something moving against the scene (0 = off).
  double motion_gate_factor = 2.0;
  // ...and keypoints with depth within moving_label_radius px of such a point, at a continuous depth,
  // share its label (0 = only the RANSAC's own points are labelled).
  double moving_label_radius = 24.0;       // px
  // After each pose optimisation, objects (depth-continuous groups of inliers off the road) whose
  // residuals err together are left out and the pose optimised again (object_residuals.hpp): a car
  // ahead at about the ego speed stays inside every per-point gate. Their keypoints are labelled
  // moving. Objects are grouped as the moving labels are: within moving_label_radius px, at depths
  // within the RANSAC's tolerance.
  bool object_test = false;
  ObjectResidualOptions object_residuals;
  double ground_min_height = 0.8;          // m below the camera
  double ground_max_tilt_deg = 20.0;
  double ground_tolerance = 0.1;           // m
  int ground_min_points = 15;
  int ground_iterations = 60;
  double ransac_prior_translation = 0.3;   // m
  double ransac_prior_relative = 0.25;
  double ransac_prior_rotation_deg = 3.0;
  // Honest states (rgbl/tracking/support.hpp): a tracked frame is `ok` with at least min_ok_inliers
  // local-map inliers, min_ok_inliers_after_relocalisation for relocalisation_window frames after a
  // relocalisation (ORB-SLAM's 30 and 50 within a second; a relocalisation itself needs the latter),
  // else `weak`.
  int min_ok_inliers = 30;
  int min_ok_inliers_after_relocalisation = 50;
  int relocalisation_window = 10;          // frames
  // Step plausibility: while the velocity comes from two consecutive tracked frames, a pose may differ
  // from the constant-velocity prediction by step_tolerance + step_tolerance_relative * |predicted step|
  // + max_acceleration * dt^2 / 2 (two pose estimates' noise, the velocity's own error, and a change of
  // speed within a car's reach) and step_tolerance_rotation_deg. For a larger step the local map is
  // searched from the prediction: a plausible pose found there with an ok frame's support wins (over
  // a step off in rotation alone, with the centre within reach, only when better supported). Else
  // the step is taken with min_jump_inliers (what a relocalisation needs) and reported as a jump,
  // unless the search from the prediction ended beyond a step's reach from it and the LiDAR prefers
  // the prediction (scan_arbitration: a facade's windows one bay along); otherwise relocalisation is
  // asked as for a failed frame, and without one that explains more of it the frame is weak and
  // placed at the prediction. After a loss, a relocalisation is held to the same reach, measured from
  // the last tracked frame over the time since (Tracker::within_reach).
  bool check_steps = true;
  // A car moves along its heading: while the last frame was tracked, every pose optimisation but a
  // relocalisation's holds the step across the learned direction of travel (TravelDirection) with
  // direction_prior_sigmas; nothing along it. Learned from tracked steps of at least
  // direction_min_step_m, used once direction_learned_m of them were seen.
  bool direction_prior = true;
  MotionPriorSigmas direction_prior_sigmas;
  double direction_min_step_m = 0.2;
  double direction_learned_m = 3.0;
  double step_tolerance = 0.25;            // m
  double step_tolerance_relative = 0.1;
  double max_acceleration = 10.0;          // m/s^2, 1 g: more than a car brakes
  double step_tolerance_rotation_deg = 3.0;
  int min_jump_inliers = 50;
  // The speed over a window: a frame's centre must also be within a vehicle's reach (allowed_step over
  // the span) of where the mean velocity over speed_window_s before an anchor speed_window_s back
  // carries it (check_speed). The step check bounds one step against the last, so a run of steps each
  // within its tolerance can slide the speed down (or up) faster than a car brakes. A frame beyond
  // that reach is searched again from where the window's speed puts it, and placed there when the
  // last frame's keypoints without depth fit that clearly more often than the step (as for
  // start_doubt_s); the window's speed is then the velocity. Within one frame of the anchor it adds
  // nothing; 0 = off. (docs/accuracy.md, "The speed over a window")
  double speed_window_s = 0.3;
  // A velocity that stands on a start without one (a map's second frame, the frame after a loss or a
  // relocalisation) is in doubt for start_doubt_s seconds. Within them a contested step (refused for
  // the prediction although clearly more local-map inliers agree with it) is taken when the last
  // frame's keypoints without depth fit it and not the prediction clearly more often than the other
  // way round (matched by descriptor; a match fits a motion when it lies on the image of its ray from
  // 2 m + 1.5 |t| ahead to infinity; a sign test at three sigmas). The scene beyond the LiDAR's reach
  // cannot move with the vehicles that hold a start's depth; where it does (a truck's top above the
  // LiDAR's field of view, next to a car braking at the lights) the velocity has a history and is
  // not in doubt. 0 = off. (docs/accuracy.md, "A start in doubt for its first second")
  double start_doubt_s = 1.0;
  // Where the images leave two starts of a frame standing further apart than a step's tolerance, the
  // LiDAR decides first when it can: the frame's returns off the road that land on the last frame's
  // scan under one start only vote for it, and a start wins when the votes differ beyond chance over
  // objects, not returns (ScanVote::object_preference), and it holds on the local map. Images can
  // agree with a wrong pose (a car ahead at the ego speed, road paint repeating at the step length,
  // motion blur that looks alike at zero motion); the static world's shape does not. Else, and
  // without scans, the road re-finds and then the inliers decide, as before.
  bool scan_arbitration = true;
  ScanSampleOptions scan_sample;          // what a frame keeps of its scan (Frame::scan)
  // ...and where a frame is started against the reference keyframe (no trusted velocity, or the motion
  // model failed), the LiDAR proposes a start of its own: the step along the last camera's forward axis,
  // from 1 m back to lidar_start_max_speed times the frame time (every 0.25 m, then every 5 cm), under
  // which most of those returns land on the last scan, if it beats standing still beyond chance. At 1 Hz
  // the images may offer no start near the true motion at all. 0 = off.
  double lidar_start_max_speed = 40.0;    // m/s (144 km/h)
  // ...and so does the road: the depth RANSAC on the keypoints on the road in both frames alone
  // (ground_keypoints; guess rules, ransac_guess_min_inliers). The road does not move, and the road
  // just ahead is what vehicles in both directions hide last. Like the LiDAR's start it is searched in
  // the local map from its own pose, not refined on the brute-force matches, which hold the vehicles.
  // Traffic seed 23, frame 1: the two starts among all matches were the oncoming lanes' 2.1 m and a
  // 2.8 m sideways, 13 deg turned alias of the lane lines; the road's alone 1.1 m (truth 1.0 m).
  bool road_start = true;
  // Between two starts further apart than a step's tolerance, the last frame's keypoints without depth
  // decide where they fit one clearly more often than the other (fits_by_rays, a sign test at three
  // sigmas, as for start_doubt_s), before the LiDAR's objects (trucks at the ego speed can be most of
  // them), the road and the inliers.
  // The scene beyond the LiDAR's reach and above its field of view rarely moves with the vehicles that
  // hold a start's depth; the rays tell driving from standing and forward from backward, not the scale.
  // A start they choose against the road and the inliers is reported (TrackResult::start_by_rays) and
  // leaves its scale to the inliers within start_doubt_s.
  bool start_by_rays = true;
  // The first frame after a gap in the frames (more than gap_interval_ratio times the last frame
  // interval and at most max_gap_s; needs both scans and the LiDAR's extrinsics): the images may find
  // a look-alike stretch within the reach the gap allows (a hedge, identical blocks), so the scan is
  // registered onto the last frame's across the gap (register_across_gap, as the bridge between two
  // maps). An accepted registration replaces the constant-velocity prediction, and a pose further than
  // gap_tolerance_m / gap_tolerance_deg from it is not taken: the local map is searched from the
  // registered pose instead, and without an ok frame's support there the frame is weak, placed at it.
  // The tolerance is several times the registration's error (the jump table's bridged pairs: the
  // simulator's 24 within 0.17 m / 0.26 deg of the truth, sequence 04's within 0.20 m) and below any
  // alias a gap lets the images take (a street's repeat, metres).
  bool register_gaps = true;
  double gap_interval_ratio = 2.5;
  double max_gap_s = 5.0;
  double gap_tolerance_m = 1.0;
  double gap_tolerance_deg = 2.0;
  GapRegistrationOptions gap_registration;
  // A frame the images cannot place is lost; its pose is still a guess that matters: a new map started
  // a few frames later is anchored at it. With register_lost (needs both scans and the extrinsics, as
  // above) its scan is registered onto the last frame's, with gap_registration's checks over the time
  // between them, and an accepted registration places it instead of the constant-velocity guess and
  // becomes the velocity (a car braking in a gap in the frames no longer keeps its speed from before).
  bool register_lost = true;
  // A frame whose step the images cannot justify is kept (weak) where the constant velocity puts it;
  // with register_refused_steps its scan registered onto the last frame's places it instead, as a lost
  // frame's does, and gives the velocity. A velocity that an earlier frame got wrong (a car standing at
  // the lights, pulled 0.2 m by crossing traffic) otherwise carries every refused frame on with it.
  bool register_refused_steps = true;
  bool temporary_points = true;         // last-frame depth points without landmark join the motion model
  // Keyframe decision (SPEC section 5), ORB-SLAM's but like with like: a keyframe is due when the frame
  // tracks fewer than this share of the reference keyframe's established landmarks (seen by 3
  // keyframes, 2 while the map has two), counting only its inliers on established landmarks too.
  // ORB-SLAM counts every inlier against 0.75; on the simulator most are young landmarks that culling
  // removes, which held keyframes 10 m apart (docs/accuracy.md, "Keyframes when the established
  // landmarks thin out"). Like with like, 0.75 made 309 keyframes of 400 frames and 0.5 was worse on
  // the real drives in 4 of 5 samples; 0.3 leaves them and the 44 low-rate runs as they were.
  int max_frames_between_keyframes = 10;
  double reference_ratio_threshold = 0.3;
  double initial_reference_ratio_threshold = 0.4;  // ...while the map has one keyframe (ORB-SLAM's value)
  // Tracking fewer than this share of the reference keyframe's established landmarks makes a keyframe
  // due without waiting for max_frames_between_keyframes or idle mapping (ORB-SLAM's 0.25 for depth
  // cameras).
  double urgent_reference_ratio = 0.25;
  // ...or, when above 0, as the frame's inliers fall under this share of all the reference keyframe's
  // landmarks still in the map, young ones too. Landmarks become established only as keyframes see
  // them, so where keyframes are sparse few are, and their count alone misses the frame leaving the
  // reference's view (the simulator's traffic street without its vehicles: 3 keyframes in 80 frames,
  // tracked on 130-190 of ~1150 keypoints with depth). ORB-SLAM's urgent share for depth cameras,
  // untuned: over five samples of the accuracy suite 0.81x the stress scenarios' ATE, the plain street
  // and the real drives as before, both long loops under 0.10 m (docs/accuracy.md, "Keyframes when
  // all the reference's landmarks thin out").
  double reference_landmark_ratio = 0.25;
  int close_tracked_threshold = 100, close_untracked_threshold = 70;
  int min_keyframe_inliers = 15;
  // Threaded mapping: no keyframe while this many wait for local mapping (ORB-SLAM's 3). Without the
  // cap a lagging mapper leaves the map thin, thin maps make every frame a keyframe, and the queue
  // grows without end.
  int max_queued_keyframes = 3;
  double close_depth = 97.0;            // m; "close" points (RGB-L: bf/fx * ThDepth = 100/707 * 700)

  // The depth error bounded beyond the measured depth: denser maps hold landmarks that bundle
  // adjustment pushed far down near-parallel rays, whose metric depth error would outweigh every true match.
  // Cauchy weights after the first round: points that err together pull the pose less (docs/accuracy.md,
  // "Cauchy weights after a Huber round").
  PoseOptimizerOptions pose{.cauchy = true, .bounded_depth_error = true};

  void validate() const;
};

struct LocalMappingOptions {
  int max_new_depth_points = 1000;      // new landmarks from depth per keyframe, nearest first
  int covisible_for_fusion = 10;
  FusionOptions fusion_match;           // 3 px at level 0, Hamming <= 50
  int max_local_ba_keyframes = 10;      // optimised keyframes (the current one and its best covisible)
  int max_fixed_keyframes = 20;
  KeyframePairOptions pairs;            // the road and the tracked motion between keyframes
  // The LiDAR pair's registration (pairs.lidar_sigma_translation > 0): two keyframes a few metres
  // apart, from the tracked motion, which is within centimetres; their scans are the frames' samples
  // (every 8th return within 2-40 m, at the image's time). Kept where it is pinned down along every
  // axis, however little (registration.probe_shift_m moved along an axis loses more than
  // lidar_min_probe_loss of the points that land: a corridor loses nothing, and the pair would only
  // restate tracking's step along it; the simulator's hedge streets lose 0.001-0.16, median 0.05,
  // yet their few trunks place the step within 0.006 m of the truth, median, 0.04 m at most), and within lidar_max_change_m /
  // lidar_max_change_deg of the tracked motion (3 sigmas of the tracked motion's own pair): beyond
  // that a truck driving beside the car has pulled it (docs/accuracy.md, "Keyframes tied by their
  // scans").
  ScanRegistrationOptions lidar_registration{.min_range = 2.0, .max_range = 40.0, .reference_voxel = 0.3,
                                             .query_voxel = 0.3, .coarse_distance = 0.5, .coarse_iterations = 3,
                                             .fine_distance = 0.3, .robust_scale = 0.1};
  double lidar_min_probe_loss = 0.0;
  double lidar_max_change_m = 0.3;
  double lidar_max_change_deg = 1.0;
  double min_found_ratio = 0.25;        // landmark culling
  int min_observations = 3;             // landmark culling after 2 keyframes
  double redundant_ratio = 0.9;         // keyframe culling
  int redundant_observers = 3;
  // Keyframe culling by revisits. A place of a new keyframe: camera centres within place_distance_ratio
  // of its median keypoint depth and viewing directions within place_angle_deg, reached again after a
  // drive (along the keyframes) of at least revisit_path_ratio times that distance. A place keeps its
  // first keyframe, the new one and the newest others, max_keyframes_per_place in all. Redundancy by
  // observers alone lets a drive that passes a place again and again add keyframes on every pass.
  bool place_culling = true;
  int max_keyframes_per_place = 2;
  double place_distance_ratio = 0.1;
  double place_angle_deg = 10.0;
  double revisit_path_ratio = 3.0;
  // After each local BA, every adjusted landmark's depth sigmas scaled by how far its depths disagree
  // with its keyframes' parallax (depth_consistency_scale, map/depth_consistency.hpp).
  bool depth_consistency = false;
  // Landmarks triangulated between the keyframe and its covisible ones for keypoints without depth
  // (triangulate_landmarks, map/triangulation.hpp); under the same culling as the depth landmarks.
  bool triangulation = false;
  TriangulationOptions triangulation_match;
  // A triangulated landmark is kept only when the keyframe's fusion finds it in this many keyframes
  // (2: the two it was made from are enough).
  int triangulation_min_views = 3;
  bool local_ba = true;
  bool keyframe_culling = true;
  bool fusion = true;
  BundleAdjustmentOptions ba;

  void validate() const;
};

}  // namespace rgbl
