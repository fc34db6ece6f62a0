#pragma once
// Loop closing, one keyframe at a time: a place is recognised from the keyframe's LiDAR scan (Scan
// Context, no training) and from its ORB descriptors (a bag of binary words), the candidates are verified geometrically with metric depth, a loop is
// accepted only when consecutive keyframes verify it, and the map is then corrected by pose-graph
// optimisation over the essential graph (keyframes and landmarks move together; frames tracked
// against a keyframe follow it).
//
// After the pose graph, the landmarks seen on one side of the loop are fused with those on the other
// (the loop's duplicates become one landmark, observed from both laps), and a bundle adjustment of
// the whole map (of the closing keyframe's spanning tree) then refines every keyframe and landmark
// against all observations, old lap and new.
//
// A loop whose matched place lies in another map (one started after a loss) merges the two: the
// current map moves rigidly onto the other, its root hangs from the matched keyframe, and the same
// correction follows.
//
// A map started after a loss is also bridged to the map before it when the drive does not return:
// the new map's first keyframe's LiDAR scan is registered onto the old map's last keyframe's scan
// from the motion model's guess over the gap (point-to-plane ICP), and the two maps merge on that
// registration when it is a clear optimum (scan_registration.hpp) and within what the guess can be off.
//
// In a thread of its own (System with threaded mapping), detect() and correct() are called apart.

#include "rgbl/backend/bundle_adjustment.hpp"
#include "rgbl/backend/loop_correction.hpp"
#include "rgbl/backend/map_bundle.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/loop/verification.hpp"
#include "rgbl/map/fusion.hpp"
#include "rgbl/map/map.hpp"
#include "rgbl/place/place_recognition.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <string>
#include <optional>
#include <unordered_map>
#include <vector>

namespace rgbl {

// Bridging a gap: the scans of the last keyframe before a loss and the first keyframe of the map
// started after it, registered from the motion model's guess (docs/loop-closing.md, "Bridging a gap").
struct MapBridgeOptions {
  bool enabled = true;
  double max_gap_s = 5.0;  // between the two keyframes' timestamps: beyond, the scans share too little
  // What the guess over the gap can be off, how far the registration searches, and what it must
  // pass to move the new map (a clear, pinned-down optimum within that reach).
  GapRegistrationOptions registration;

  void validate() const;
};

// A loop's relative poses measured again by the LiDAR: the images' verification leans on the matched
// place's landmarks, whose own errors (made when the map was young, seen from far) can put a short
// loop's measurement further off than the map has drifted (docs/loop-closing.md, "Loops measured by
// the scans"); the two keyframes' scans, registered from it, do not share those errors.
struct LoopScanOptions {
  bool enabled = true;
  // Every keyframe keeps its scan as one point per voxel of this edge (the registration's reference
  // voxel, so a stored reference registers as the full scan would): 10-16k points, about 0.22 MB, on
  // KITTI.
  double voxel = 0.5;  // m
  // The registration must converge from the images' measurement, be a clear optimum (moved by 1 m
  // along any axis it loses at least min_probe_loss of its landing points, as the gap registration
  // asks) and stay within max_change of the images' measurement: ICP's coarse correspondences reach
  // 1.5 m, and a result beyond this is another optimum, not a refinement.
  double min_probe_loss = 0.1;
  double max_change_m = 1.0;
  double max_change_deg = 3.0;
  ScanRegistrationOptions registration;

  void validate() const;
};

struct LoopClosingOptions {
  bool enabled = true;
  // Place recognition: the candidates of every recogniser named in places.methods (Scan Context on
  // the keyframe's LiDAR scan, a bag of words on its descriptors) are fused and verified.
  PlaceRecognitionOptions places;
  std::size_t max_candidates = 3;  // best places verified per keyframe and recogniser
  // The keyframe's best covisible keyframes (most shared landmarks) shown to the recognisers as what
  // the place looks like from nearby (the bag of words' bar: a candidate must look at least as similar
  // as the least similar of them).
  std::size_t place_neighbours = 10;
  // Candidates are keyframes at least this many keyframes older than the query and not covisible with
  // it: a recent keyframe is the local map's business, not a loop's.
  int min_keyframe_gap = 10;
  // Keyframe pairs that must each verify the loop (ORB-SLAM: 3 keyframes) and agree on it: this
  // keyframe with the matched one, then the keyframes before this one with the matched one, their
  // loop-measured poses relative to this keyframe within the tolerances below of the map's. Where one
  // of those does not see the place (a drive that ends where it began: the keyframes before the last
  // are behind the first keyframe, and the pyramid's 3.6x scale range does not reach the places it
  // saw), this keyframe verified against the matched keyframe's best covisible ones counts instead,
  // its pose from each within the same tolerances of the first verification's. A keyframe that sees
  // the place but disagrees refuses the loop.
  int consistent_keyframes = 3;
  std::size_t matched_side_keyframes = 5;  // best covisible keyframes of the matched one tried (0: none)
  double consistency_tolerance_m = 0.2;
  double consistency_tolerance_deg = 1.0;
  // A verified loop changes the map only when the map disagrees with it by more than this: about 5x the
  // verification's precision measured on real data (2.2 cm, 0.5 deg at 16 m). Below, it is recorded as
  // confirming the map.
  double min_correction_m = 0.1;
  double min_correction_deg = 0.5;
  // Odometry drifts, it does not jump: a verified loop is refused when it would move the current
  // keyframe further than odometry can have drifted over the distance driven since the matched
  // keyframe (along the keyframes as they were placed), i.e. more than drift_allowance_m +
  // max_drift_percent % of it, or turn it more than drift_allowance_deg + max_drift_deg_per_100m per
  // 100 m. A look-alike place (a street of identical blocks) verifies as well as a true one, but asks
  // for a correction as long as the way back to it. The bounds are several times the worst drift
  // rgbl shows on any excerpt or scenario (docs/loop-closing.md); a true loop after more drift than
  // that is refused too, the safe side: a false closure wrecks the map.
  double max_drift_percent = 10.0;
  double max_drift_deg_per_100m = 10.0;
  double drift_allowance_m = 1.0;
  double drift_allowance_deg = 2.0;
  // Map merging: a loop verified against a place of another map (one started after a loss, or the map
  // such a map was started from) moves the current map onto it rigidly (metric depth: no scale) and
  // joins the two; the same checks as a loop decide.
  bool merge_maps = true;
  MapBridgeOptions bridge;  // merging across a gap the drive never returns to (needs merge_maps)
  LoopScanOptions scans;    // the loop's relative poses refined by the keyframes' scans (needs the LiDAR)
  LoopVerificationOptions verification;
  LoopCorrectionOptions correction;
  // Fusion across the loop: the landmarks of the matched keyframe and its fusion_neighbours best
  // covisible ones are fused into the closing keyframe and its fusion_neighbours best covisible ones.
  bool fuse = true;
  int fusion_neighbours = 10;
  FusionOptions fusion;
  // Bundle adjustment of the whole map after a closure (its spanning-tree root held fixed).
  bool global_ba = false;
  BundleAdjustmentOptions global_ba_options = {.iterations = 10, .dense_schur = false};
  // A keyframe takes part in it only with at least this many observations of landmarks that other
  // keyframes see too (the evidence the tracker asks of a frame to call it ok); one with fewer is
  // held and then moved rigidly with its spanning-tree parent.
  int global_ba_min_shared = 30;
  // The road and the tracked motion between keyframes, as local BA has them (the same defaults):
  // without them keyframes that share few landmarks slide against each other (400 m loop: ATE 0.335
  // m with global BA, 0.182 m with the pairs; docs/loop-closing.md).
  KeyframePairOptions global_ba_pairs;

  void validate() const;
};

// One closure: the map corrected through a loop.
struct LoopClosure {
  std::size_t frame_index = 0;          // of the keyframe that closed it
  std::size_t matched_frame_index = 0;  // of the older keyframe it matched
  KeyframeId current, matched;
  bool merged = false;                  // the loop joined two maps (matched lies in the older one)
  bool bridged = false;                 // and that merge came from registering the scans across a gap
  std::string place_source;             // the recogniser that found the matched place
  double place_similarity = 0.0;        // its score for it, in [0, 1]
  int inliers = 0;                      // of the verification
  double correction_m = 0.0;            // how far the current keyframe moved
  double correction_deg = 0.0;          // and turned
  double time_ms = 0.0;                 // detection, verification and correction of this keyframe
  LoopCorrectionResult correction;
  int fused_landmarks = 0;              // duplicates across the loop made one, observations added
  int global_ba_keyframes = 0;          // keyframes and landmarks in the global bundle adjustment
  int global_ba_landmarks = 0;
  int global_ba_held = 0;               // of those keyframes, held for too little shared evidence
  int global_ba_outliers = 0;           // observations it erased
  double global_ba_ms = 0.0;
};

// What one keyframe did in the loop closer (also when nothing was closed).
struct LoopCloserStep {
  int candidates = 0;      // places the recognisers proposed, verified
  int verified = 0;        // of those, verified geometrically
  int implausible = 0;     // of those, refused: more correction than odometry can have drifted
  bool consistent = false; // a loop confirmed by consistent_keyframes keyframe pairs that agree
  double time_ms = 0.0;
  std::optional<LoopClosure> closure;
};

// A loop detect() confirmed, not yet applied to the map.
struct DetectedLoop {
  KeyframeId keyframe;                      // the current keyframe
  LoopVerification verification;            // against the matched keyframe
  PlaceCandidate place;                     // how the matched keyframe was found
  std::vector<LoopConstraint> confirmations;  // of the keyframe pairs that confirmed it
  bool bridge = false;                      // a new map bridged to the one before it (MapBridgeOptions)
};

// The loop closer's counts over a run (what it considered, not only what it closed).
struct LoopClosingStats {
  int keyframes = 0;    // processed
  int candidates = 0;   // places verified
  int verified = 0;     // verified geometrically
  int implausible = 0;  // verified, but refused: more correction than odometry can have drifted
  int consistent = 0;   // keyframes whose best loop held over consistent_keyframes keyframe pairs
  int confirming = 0;   // of those, loops that agreed with the map (no correction)
  int closures = 0;     // of those, loops the map was corrected with
  int merges = 0;       // of those, closures that joined two maps
  int bridge_attempts = 0;  // new maps whose first scan was registered onto the map before
  int bridges = 0;          // of the merges, those by such a registration
  int scan_refined = 0;     // loop constraints (of consistent loops) the scans measured again...
  int scan_kept = 0;        // ...and those the scans could not (the images' measurement kept)
  double time_ms = 0.0; // detection, verification and correction over the run (threaded: off the tracking path)
};

class LoopCloser {
 public:
  // Creates the recognisers options.places.methods names (ConfigError / ParseError as
  // make_place_recognizer). With the LiDAR's extrinsics (calibration.T_cam_lidar) maps started after a
  // loss are bridged (MapBridgeOptions); with a camera alone they are not.
  LoopCloser(const CameraCalibration& calibration, LoopClosingOptions options);
  LoopCloser(const PinholeCamera& camera, LoopClosingOptions options);
  // Adds a recogniser of your own; its candidates are fused with the others'. Before the first process().
  void add_place_recognizer(std::unique_ptr<PlaceRecognizer> recognizer);
  // The bridge between two maps registers the scans on `pool` (a search from dozens of starts, a few
  // hundred ms inline on KITTI's scans); the result is the same with any pool or none (nullptr: inline).
  void use_task_pool(std::shared_ptr<TaskPool> pool) { pool_ = std::move(pool); }

  // Call once per new keyframe, in order, after local mapping has processed it. `scan` is the
  // keyframe's LiDAR scan (empty: only the recognisers that need none see it). Takes the map's lock itself: shared
  // while detecting, exclusive while correcting.
  LoopCloserStep process(Map& map, KeyframeId keyframe, PointCloudView scan);

  // process() in two halves, for a loop closer in a thread of its own: detect() holds the map's lock
  // shared (tracking and mapping go on) and fills `loop` with a confirmed loop that disagrees with the
  // map, or leaves it empty; correct() applies it and must be called with the map's lock held
  // exclusively, while neither mapping nor tracking is between reading and writing the map. It
  // re-checks that both keyframes still exist (mapping may have culled one meanwhile) and may still
  // find that the loop only confirms the map. Both add to `step`.
  LoopCloserStep detect(Map& map, KeyframeId keyframe, PointCloudView scan, std::optional<DetectedLoop>& loop);
  void correct(Map& map, const DetectedLoop& loop, LoopCloserStep& step);

  // Every loop the map has been corrected with (kept: later corrections must respect earlier loops).
  const std::vector<LoopConstraint>& loops() const { return loops_; }
  const LoopClosingOptions& options() const { return options_; }
  const LoopClosingStats& stats() const { return stats_; }

 private:
  PinholeCamera camera_;
  std::optional<Eigen::Isometry3d> T_cam_lidar_;  // none: no bridging
  std::shared_ptr<TaskPool> pool_;
  // Each keyframe's scan, voxel-downsampled (LoopScanOptions), by keyframe id; dropped with the keyframe.
  std::unordered_map<int, std::vector<LidarPoint>> scans_;
  // The constraint re-measured by the scans of its two keyframes (`current_scan` for the current one
  // when given), or nullopt when they cannot (LoopScanOptions' checks).
  std::optional<LoopConstraint> scan_refined(const LoopConstraint& c, PointCloudView current_scan) const;
  // Keeps this keyframe's scan and drops those of keyframes no longer in the map.
  void keep_scan(const Map& map, KeyframeId keyframe, PointCloudView scan);
  LoopClosingOptions options_;
  std::vector<std::unique_ptr<PlaceRecognizer>> places_;
  std::vector<LoopConstraint> loops_;
  LoopClosingStats stats_;
  // Distance driven up to each processed keyframe (by id; NaN: not processed), along the keyframes as
  // they were placed, and where the last one was.
  std::vector<double> driven_m_;
  double driven_total_m_ = 0.0;
  std::optional<Eigen::Vector3d> last_centre_;
  // Adds the way from the last processed keyframe to `centre`; the distance driven up to `keyframe`.
  double record_odometry(KeyframeId keyframe, const Eigen::Vector3d& centre);
  // The latest consistent_keyframes keyframes processed, oldest first (one spare for a culled one).
  std::vector<KeyframeId> recent_;
  void remember(KeyframeId keyframe);
  // The last processed keyframe and its scan (for bridging: the old map's last, when a new one starts).
  // The copy costs 0.07 ms per keyframe for KITTI's 123k points (its capacity reused).
  KeyframeId last_keyframe_;
  std::vector<LidarPoint> last_scan_;
  void adjust_map(Map& map, KeyframeId keyframe, LoopClosure& closure) const;
  // correct() without its timing.
  void apply(Map& map, const DetectedLoop& loop, LoopCloserStep& step);
};

}  // namespace rgbl
