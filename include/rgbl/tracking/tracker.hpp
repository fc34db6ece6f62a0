#pragma once
// The tracking state machine: not initialised -> ok <-> lost. Each frame is matched against the map
// (motion model, reference-keyframe fallback, local map, relocalisation) and its pose optimised; a
// suspect motion-model pose is checked by relocalisation, and a camera lost where the map cannot place
// it starts a new map. The tracker also decides when a frame becomes a keyframe. It never throws on bad
// input: failure is a state.
//
// Each way of placing a frame is a Hypothesis built as a value by const members; track() chooses one
// and commit() makes it the tracker's state, once. The local-map searches of every hypothesis tried
// count towards the landmarks' visible/found ratios (committed with the frame).

#include "rgbl/backend/pose_optimizer.hpp"
#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/map/map.hpp"
#include "rgbl/tracking/frame.hpp"
#include "rgbl/tracking/options.hpp"
#include "rgbl/tracking/support.hpp"

#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace rgbl {

struct RayFits;  // tracking/frame_motion.hpp

class TaskPool;

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
  bool step_registered = false;  // ...or by its scan (TrackerOptions::register_refused_steps)
  // ...or the step was refused although clearly more local-map inliers (two sigmas) agree with it than
  // with the pose kept: the frame is weak (the evidence contradicts its pose)
  bool step_contested = false;
  // A contested step taken within start_doubt_s of a start without velocity: the start was wrong, and
  // the frames since this index were placed on it (they stay where they are).
  std::optional<std::size_t> start_refuted_since;
  // The speed had changed faster than a vehicle can (check_speed over TrackerOptions::speed_window_s)
  // and the keypoints without depth took the frame's pose within reach of the speed before the slide.
  bool speed_corrected = false;
  // A start without velocity chosen by the keypoints without depth against the road and the inliers
  // (TrackerOptions::start_by_rays): its scale is unchecked.
  bool start_by_rays = false;
  // A suspect motion-model pose kept because the frame's scan registered onto the last one near it
  // (TrackerOptions::confirm_suspect_by_scan), where it would have been lost.
  bool scan_confirmed = false;
  // The first frame after a gap in the frames (TrackerOptions::register_gaps): its scan was registered
  // onto the last frame's; gap_registered: accepted, the registration was the prediction.
  bool gap = false;
  bool gap_registered = false;
  // A lost frame placed by its scan's registration onto the last frame's (TrackerOptions::register_lost)
  bool lost_registered = false;
};

class Tracker {
 public:
  // T_cam_lidar: the LiDAR's extrinsics, for registering the scans across a gap in the frames
  // (TrackerOptions::register_gaps); none: no registration.
  Tracker(Map& map, const PinholeCamera& camera, TrackerOptions options,
          std::optional<Eigen::Isometry3d> T_cam_lidar = std::nullopt);

  // Tracks the frame (sets frame.T_cam_world, landmarks, outliers). When initialised_now or
  // need_keyframe, the caller turns the frame into a keyframe with make_keyframe(). mapping_idle and
  // keyframes_queued: local mapping's state (threaded; inline it is always idle with none queued).
  // scan: the frame's LiDAR scan in its own frame (empty: none), copied for the next frame.
  TrackerOutcome track(Frame& frame, bool mapping_idle, std::size_t keyframes_queued = 0, PointCloudView scan = {});

  // Adds the frame as a keyframe to the map (taking the map lock) and makes it the reference.
  KeyframeId make_keyframe(const Frame& frame);

  // Work that splits runs on `pool` (the scans' registration across a gap in the frames, a few
  // hundred ms inline); results are the same with any pool or none (nullptr: inline).
  void use_task_pool(std::shared_ptr<TaskPool> pool) { pool_ = std::move(pool); }

  // The map was corrected (a loop closed): the reference keyframe, which was at T_ref_world_before,
  // moved, and the last frames move with it so that the next prediction lands on the corrected map.
  // Returns that move as D (a frame's T_cam_world becomes T_cam_world * D); nullopt without a reference.
  std::optional<Eigen::Isometry3d> follow_map_correction(const Eigen::Isometry3d& T_ref_world_before);


  TrackState state() const { return state_; }
  KeyframeId reference_keyframe() const { return reference_; }
  // Constant-velocity motion T_cur_last of the last tracked frame pair, if any.
  const std::optional<Eigen::Isometry3d>& velocity() const { return velocity_; }
  double velocity_dt() const { return velocity_dt_; }  // s between the frames of velocity()

 private:
  // What a local-map search around a frame's pose found.
  struct LocalMapResult {
    bool ok = false;
    int inliers = 0;
    int visible = 0;       // local-map points predicted in view (searched for)
    KeyframeId reference;  // the keyframe sharing most points with the frame (else the one searched around)
  };
  // The landmarks the local-map searches of one frame predicted in view and matched. Their visible and
  // found counts (which decide culling) are committed with the frame, for every search it made.
  struct ViewLog {
    std::vector<LandmarkId> visible, found;
  };
  // One placement of the frame and the tracker state that comes with it if it is chosen.
  struct Hypothesis {
    Frame frame;
    bool ok = false;
    bool weak = false;         // kept on frame-to-frame motion alone, or placed at the prediction
    bool relocalised = false;  // placed against the whole map
    bool jump = false;           // a step beyond a vehicle's reach, taken on strong evidence
    bool step_rejected = false;  // ...on weak evidence: placed at the prediction
    bool step_registered = false;  // ...or by its scan (TrackerOptions::register_refused_steps)
    // a step beyond reach refused for the prediction's pose though clearly more inliers agree with it:
    // weak, but no keyframe for it (the frame adds nothing the map lacks, its pose is the one in doubt)
    bool step_contested = false;
    bool start_refuted = false;  // ...taken, within start_doubt_s of a start (start_)
    // a start chosen by the keypoints without depth against the road and the inliers (start_by_rays):
    // its direction stands on the rays, its scale on nothing yet
    bool start_by_rays = false;
    bool scan_confirmed = false;  // a suspect pose kept on the scan's registration (confirm_by_scan)
    // a step within reach of the last one but not of the speed over a window (check_speed): placed
    // where the local map searched from the window's prediction ends; that velocity is kept
    std::optional<Eigen::Vector3d> speed_placed;  // the window's velocity, m/s in the world frame
    int inliers = 0;
    KeyframeId reference;                   // the reference keyframe it leaves
    std::size_t relocalisation_frame = 0;   // the last relocalisation, this frame's if it made one
  };
  // The first hypothesis (motion model, reference keyframe, or relocalisation when lost) and the
  // evidence that decides whether a second one is needed.
  struct FirstHypothesis {
    Hypothesis hypothesis;
    bool motion_ok = false;  // frame-to-frame motion found enough inliers
    int motion_inliers = 0;
    bool recent_loss = false;
    bool relocalisation_tried = false;
    bool suspect = false;    // motion-model pose disagreeing with the map or the recent frames
    LocalMapResult local;
  };
  // Constant-velocity prediction of the frame's pose.
  struct Prediction {
    Eigen::Isometry3d T_last_world = Eigen::Isometry3d::Identity();  // the last frame's pose
    Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();   // over the time elapsed since
    bool gap = false;         // the first frame after a gap, its scan registered (register_gap)
    bool registered = false;  // ...and T_cam_world is that registration
    // register_onto_last's result from this guess, once asked: a suspect frame's registration is the
    // one its loss or its refused step would ask again
    bool onto_last_tried = false;
    std::optional<Eigen::Isometry3d> onto_last;
  };

  TrackerOutcome track_frame(Frame& frame, bool mapping_idle, std::size_t keyframes_queued, PointCloudView scan);
  Prediction predict(const Frame& frame) const;
  // After a gap in the frames: the prediction replaced by the scan's registration onto the last
  // frame's, when it is accepted (TrackerOptions::register_gaps).
  void register_gap(const Frame& frame, PointCloudView scan, Prediction& prediction) const;
  // A frame the images cannot place: the same registration, from the constant-velocity guess over the
  // time since the last frame (TrackerOptions::register_lost).
  void register_lost(const Frame& frame, PointCloudView scan, Prediction& prediction) const;
  // The frame's scan registered onto the last frame's from the prediction, with gap_registration's
  // checks: the frame's pose when accepted. `what` names the frame's case in the log. Registered once
  // per prediction (Prediction::onto_last), whichever case asks first.
  std::optional<Eigen::Isometry3d> register_onto_last(const Frame& frame, PointCloudView scan,
                                                      Prediction& prediction, const char* what) const;
  // TrackerOptions::confirm_suspect_by_scan: right after a tracked frame, a suspect hypothesis whose
  // frame's scan registers onto the last one (register_onto_last) kept when within a step's reach of
  // the registration, or moved to where the local map searched from the registration ends there;
  // false (the frame lost) otherwise.
  bool confirm_by_scan(Hypothesis& h, PointCloudView scan, Prediction& prediction, ViewLog& views) const;
  // TrackerOptions::register_refused_steps: a frame whose step was refused placed by its scan.
  void register_refused_step(Hypothesis& h, PointCloudView scan, Prediction& prediction) const;
  // A pose after a gap further from the registered prediction than the gap tolerance: the local map
  // searched from the registration instead, else the frame weak at the registered pose.
  Hypothesis gap_hypothesis(Hypothesis h, const Prediction& prediction, ViewLog& views) const;
  // The local map searched for a copy of `frame` from T_cam_world, its matches cleared first: the
  // alternative pose that the step, speed and gap checks weigh against the frame's own.
  struct Search {
    Frame frame;
    ViewLog views;
    LocalMapResult local;
  };
  Search search_from(const Frame& frame, const Eigen::Isometry3d& T_cam_world, KeyframeId reference,
                     std::size_t relocalisation_frame) const;
  // The end of those checks: the frame as the search left it when `take`, else weak at T_cam_world
  // without matches; the search's views are counted either way.
  static void settle(Hypothesis& h, Search search, bool take, const Eigen::Isometry3d& T_cam_world, ViewLog& views);
  FirstHypothesis first_hypothesis(Frame frame, const Prediction& prediction, ViewLog& views) const;
  // Relocalisation against the whole map, independent of any prediction, confirmed on the local map.
  Hypothesis relocalisation_hypothesis(Frame frame, KeyframeId reference, ViewLog& views) const;
  // What the LiDAR's say reads, built once per frame when first needed: the last frame's scan indexed
  // and the frame's returns off the road (see TrackerOptions::scan_arbitration).
  struct LidarView {
    ScanAgreement last;
    ScanSample evidence;
    std::vector<std::uint32_t> objects;  // label_objects(evidence), when a vote first needs them
  };
  // The view, built into `cache` on the first call; nullptr without scan_arbitration or either scan.
  const LidarView* lidar_view(std::optional<LidarView>& cache, const Frame& frame) const;
  // The LiDAR's say between two poses of `frame`: +1 for b, -1 for a, 0 when it is not decisive or it
  // has no view. a and b name them in the log. by_objects: decisive only with objects, not returns,
  // as the independent units (ScanVote::object_preference).
  int lidar_preference(std::optional<LidarView>& cache, const Frame& frame, const Eigen::Isometry3d& T_a_world,
                       const Eigen::Isometry3d& T_b_world, const char* a, const char* b, bool by_objects) const;
  // The last frame's keypoints without depth matched into `frame` and tested on two poses of it
  // (fits_by_rays, the motions from the last frame).
  RayFits fits_from_last(const Frame& frame, const Eigen::Isometry3d& T_a_world, const Eigen::Isometry3d& T_b_world) const;
  // A pose of the frame beyond a vehicle's reach of the prediction (check_step's translation) whose
  // scan lands better on the last frame's from the prediction; `what` names the pose in the log.
  bool scans_prefer_prediction(std::optional<LidarView>& cache, const Frame& frame,
                               const Eigen::Isometry3d& T_cam_world, const Prediction& prediction,
                               const char* what) const;
  // A relocalisation of the frame after a tracked one that the scans vote against (scans_prefer_prediction,
  // under the step check's conditions: check_steps, a steady velocity, not after a registered gap).
  bool scans_refuse_relocalisation(const Hypothesis& relocalised, const Prediction& prediction) const;
  // The LiDAR's own start for `frame` (see TrackerOptions::lidar_start_max_speed) as T_cur_last.
  std::optional<Eigen::Isometry3d> lidar_start(std::optional<LidarView>& cache, const Frame& frame) const;
  // A step beyond a vehicle's reach on weak evidence: the local map searched from the prediction
  // instead, else relocalisation (unless tried already), else the frame placed at the prediction.
  Hypothesis step_hypothesis(Hypothesis h, const Prediction& prediction, bool relocalisation_tried,
                             ViewLog& views) const;
  // A step within reach of the last one that the speed over a window refutes (speed): the local map
  // searched from where that speed puts the frame instead, taken when it ends within the window's
  // reach and the keypoints without depth fit it clearly more often than the step.
  Hypothesis speed_hypothesis(Hypothesis h, const Prediction& prediction, const SpeedCheck& speed,
                              ViewLog& views) const;
  // Makes the chosen hypothesis the tracker's state (the only place track() changes it).
  void commit(Hypothesis& h, const Prediction& prediction, const FirstHypothesis& first, const ViewLog& views,
              bool mapping_idle, std::size_t keyframes_queued, TrackerOutcome& outcome);

  bool initialise(Frame& frame, const Eigen::Isometry3d& T_cam_world);
  // The frame started a map (the first, or a new one when lost): it is the last frame and tracked.
  TrackerOutcome& finish_initialised(const Frame& frame, TrackerOutcome& outcome);
  // Returns the pose inliers (landmarks and temporary points), 0 when matching failed.
  // Guided matching against `reference` (the last frame, or after a loss the last tracked one) from
  // T_guess, refined by the frame-to-frame motion from depth (constrained to `prior` if given).
  int track_with_motion_model(Frame& frame, const Frame& reference, const Eigen::Isometry3d& T_guess,
                              const std::optional<Eigen::Isometry3d>& prior) const;
  // The velocity as a motion prior: only while it comes from two consecutive tracked frames.
  std::optional<Eigen::Isometry3d> trusted_velocity() const {
    return options_.ransac_motion_prior && velocity_steady_ ? velocity_ : std::nullopt;
  }
  // Another start against the reference keyframe: from a depth consensus too weak to be the only
  // start, or (rival) from a second rigid motion among the matches, or (rival, as proposed) the road's or the LiDAR's
  // own start, at its pose without matches.
  struct OtherStart {
    enum class Source {
      weak_consensus,  // the depth consensus below ransac_guess_min_inliers
      second_motion,   // the second rigid motion among the matches
      road,            // the road's keypoints alone (road_start)
      lidar,           // the LiDAR's own start (lidar_start_max_speed)
    };
    Frame frame;
    Source source = Source::weak_consensus;
    // a rival motion; the weak consensus is the same matches' motion, found again
    bool rival() const { return source != Source::weak_consensus; }
    // the road's and the LiDAR's starts are searched in the local map from their pose as proposed,
    // never refined on the brute-force matches (which hold the vehicles)
    bool as_proposed() const { return source == Source::road || source == Source::lidar; }
    const char* name() const;
  };

  // Matches the reference keyframe's points by descriptor and optimises the pose. `others` receives the
  // other starts that converged too (the weak consensus first), and the road's and the LiDAR's starts as they are.
  bool track_reference_keyframe(Frame& frame, std::vector<OtherStart>& others,
                                std::optional<LidarView>& lidar) const;
  // Unmatches keypoints labelled moving and those whose landmark disagrees with frame.T_cam_world (a
  // depth-consensus prediction; see disagrees_with_pose).
  void drop_moving_matches(Frame& frame, double slack = 0.0) const;
  // Keypoint i against world point p_world seen from frame.T_cam_world: in 3-D where it has depth
  // (beyond slack metres more than the gate), else beyond the guided-matching radius in the image.
  bool disagrees_with_pose(const Frame& frame, std::size_t i, const Eigen::Vector3d& p_world, double slack = 0.0) const;
  // Searches the local map around `reference` (see local_map_around) from the frame's pose.
  LocalMapResult track_local_map(Frame& frame, KeyframeId reference, std::size_t relocalisation_frame,
                                 ViewLog& views) const;
  // The keyframes sharing points with the frame and their neighbours; the caller holds the map lock.
  std::pair<std::vector<KeyframeId>, KeyframeId> local_map_around(const Frame& frame, KeyframeId reference) const;
  // Landmarks of the local map around `reference` that a camera at T_cam_world would see.
  int landmarks_in_view(const Eigen::Isometry3d& T_cam_world, KeyframeId reference) const;
  // The motion-model hypothesis disagrees with the map or with the recent frames (motion_suspect);
  // keypoints: how many the frame has.
  bool suspect(int motion_inliers, const LocalMapResult& local, std::size_t keypoints) const;
  bool relocalise(Frame& frame) const;
  // The local-map search from a relocalised pose re-finds enough of the points it predicts visible.
  bool relocalisation_confirmed(const LocalMapResult& local) const;
  // After a loss: is a relocalised pose where the vehicle can be since the last tracked frame?
  bool within_reach(const Frame& frame, const Prediction& prediction) const;
  // extra: (keypoint, world point) correspondences that are not landmarks (temporary points). The
  // direction prior holds while the last frame was tracked, except for a relocalisation (which must
  // not lean on the last pose).
  int optimise_pose(Frame& frame, const std::vector<std::pair<std::size_t, Eigen::Vector3d>>& extra = {},
                    bool relocalising = false) const;
  // TrackerOptions::direction_prior for a frame after last_frame_, if it applies.
  std::optional<PoseMotionPrior> motion_prior() const;
  // TrackerOptions::object_test after a pose optimisation (at T_cam_world, with its inliers): removes
  // the observations of objects that err together, labels their keypoints moving and outliers and
  // their landmarks moved. True when it removed any (the pose is then optimised again).
  bool leave_out_erring_objects(Frame& frame, std::vector<PoseObservation>& observations,
                                std::vector<std::size_t>& keypoint_of, const Eigen::Isometry3d& T_cam_world,
                                const std::vector<bool>& inlier) const;
  bool need_keyframe(const Frame& frame, int inliers, bool mapping_idle) const;
  std::optional<std::size_t> frames_since_relocalisation(const Frame& frame) const {
    return frames_since(frame, last_relocalisation_frame_);
  }
  static std::optional<std::size_t> frames_since(const Frame& frame, std::size_t relocalisation_frame) {
    if (relocalisation_frame == 0 || frame.index < relocalisation_frame) return std::nullopt;
    return frame.index - relocalisation_frame;
  }

  Map& map_;
  PinholeCamera camera_;
  TrackerOptions options_;
  std::optional<Eigen::Isometry3d> T_cam_lidar_;
  std::shared_ptr<TaskPool> pool_;
  std::vector<LidarPoint> last_scan_;  // the last frame's, when gaps are registered
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
  TravelDirection travel_;  // the direction prior's direction
  // the last frame placed without a steady velocity: the velocity is in doubt (start_doubt_s) since
  struct Start {
    double time = 0.0;
    std::size_t frame = 0;
    bool by_rays = false;  // Hypothesis::start_by_rays
  };
  std::optional<Start> start_;
  std::vector<PlacedCentre> recent_;  // consecutive tracked frames since the last start, jump or gap (check_speed)
};

}  // namespace rgbl
