#include "rgbl/tracking/tracker.hpp"

#include "matching.hpp"
#include "rgbl/backend/pose_optimizer.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/map/landmark_view.hpp"
#include "rgbl/tracking/frame_motion.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <shared_mutex>
#include <span>
#include <utility>

namespace rgbl {

namespace {

// Clearly more inliers on a step than on the pose kept instead: two sigmas of the counts' difference,
// each count taken as Poisson (a few inliers either way are a tie).
bool clearly_more(int step_inliers, int kept_inliers) {
  return count_preference(static_cast<std::size_t>(kept_inliers), static_cast<std::size_t>(step_inliers), 2.0) > 0;
}

// The frame's observations as a new keyframe (landmark links are added by the caller).
Keyframe keyframe_from(const Frame& frame, const TrackerOptions& options) {
  Keyframe kf;
  kf.frame_index = frame.index;
  kf.timestamp = frame.timestamp;
  kf.T_cam_world = frame.T_cam_world;
  kf.keypoints = frame.keypoints;
  kf.descriptors = frame.descriptors;
  kf.depth = frame.depth;
  kf.depth_sigma = frame.depth_sigma;
  kf.depth_refused = frame.depth_refused;
  if (frame.scan_at_image_time) kf.scan = frame.scan;
  // the road under it, which ties it to the keyframes before it in local BA
  if (frame.scan) {
    if (const auto road = road_plane(*frame.scan, options)) kf.road = Eigen::Vector4d(road->n.x(), road->n.y(), road->n.z(), road->d);
  }
  // a point on a moving object is no landmark: without usable depth, local mapping makes none from it
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.is_moving(i)) kf.depth_sigma[i] = 0.0F;
  }
  return kf;
}

}  // namespace

Tracker::Tracker(Map& map, const PinholeCamera& camera, TrackerOptions options,
                 std::optional<Eigen::Isometry3d> T_cam_lidar)
    : map_(map), camera_(camera), options_(options), T_cam_lidar_(T_cam_lidar) {
  options_.validate();
}

namespace {

double level_scale(const Map& map, int level) { return std::pow(map.options().scale_factor, level); }

void clear_matches(Frame& frame) {
  std::fill(frame.landmarks.begin(), frame.landmarks.end(), LandmarkId{});
  std::fill(frame.outlier.begin(), frame.outlier.end(), false);
  frame.moving.clear();  // labels belong to the motion hypothesis being discarded
  frame.moved_landmarks.clear();
}

void discard_outliers(Frame& frame) {
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.outlier[i]) {
      frame.landmarks[i] = LandmarkId{};
      frame.outlier[i] = false;
    }
  }
}

int count_tracked(const Frame& frame) {
  return static_cast<int>(std::count_if(frame.landmarks.begin(), frame.landmarks.end(), [](LandmarkId l) { return l.valid(); }));
}

}  // namespace

// Hypotheses are built as values by const members (first, maybe relocalisation, maybe the step
// check's), the chosen one is committed once: nothing but commit() and initialisation changes state.
TrackerOutcome Tracker::track(Frame& frame, bool mapping_idle, std::size_t keyframes_queued, PointCloudView scan) {
  TrackerOutcome outcome = track_frame(frame, mapping_idle, keyframes_queued, scan);
  const bool registers = options_.register_gaps || options_.register_lost || options_.register_refused_steps ||
                         options_.confirm_suspect_by_scan;
  if (registers && T_cam_lidar_) last_scan_.assign(scan.begin(), scan.end());
  return outcome;
}

TrackerOutcome Tracker::track_frame(Frame& frame, bool mapping_idle, std::size_t keyframes_queued,
                                    PointCloudView scan) {
  TrackerOutcome outcome;
  frame.landmarks.assign(frame.size(), LandmarkId{});
  frame.outlier.assign(frame.size(), false);
  frame.moving.clear();
  frame.moved_landmarks.clear();
  if (state_ == TrackState::NotInitialised) {
    if (initialise(frame, Eigen::Isometry3d::Identity())) return finish_initialised(frame, outcome);
    outcome.state = state_;
    last_frame_ = frame;
    last_frame_->grid = FeatureGrid();
    return outcome;
  }
  Prediction prediction = predict(frame);
  register_gap(frame, scan, prediction);
  ViewLog views;
  FirstHypothesis first = first_hypothesis(std::move(frame), prediction, views);
  Hypothesis h = std::move(first.hypothesis);
  if ((first.suspect || !h.ok) && !first.relocalisation_tried) {
    // A second hypothesis from the whole map, independent of any prediction, for a suspect pose and
    // before declaring the camera lost; taken when it explains more of the frame.
    Hypothesis relocalised = relocalisation_hypothesis(h.frame, h.reference, views);
    if (relocalised.ok && relocalised.inliers > h.inliers && !scans_refuse_relocalisation(relocalised, prediction)) {
      h = std::move(relocalised);
    } else if (!relocalised.ok && first.suspect) {
      h.scan_confirmed = h.ok && confirm_by_scan(h, scan, prediction, views);
      h.ok = h.scan_confirmed;
    }
    if (first.suspect) {
      logger()->debug("frame {}: motion model suspect ({} inliers, last frame {}; local map {}/{}): {}",
                      h.frame.index, first.motion_inliers, last_inliers_, first.local.inliers, first.local.visible,
                      h.relocalised    ? "relocalised"
                      : h.scan_confirmed ? "confirmed by its scan"
                      : h.ok             ? "confirmed"
                                         : "lost");
    }
  }
  // A frame the images cannot place after a registered gap is lost all the same, at the registered
  // pose: a new map started after it is anchored there and bridged. Kept weak at that pose instead,
  // the frames after it tracked on against the old map's few points in view: further from the gapless
  // run in 4 of 9 runs of scripts/jump-table.sh (plain seed 1, 2 s: 0.27 m against 0.07 m), closer
  // in 3 (traffic seed 1, 1 s: 0.13 against 0.47 m).
  if (h.ok && prediction.registered) {
    h = gap_hypothesis(std::move(h), prediction, views);
  } else if (h.ok && options_.check_steps && velocity_steady_ && has_pose(state_) && last_frame_ && !h.relocalised) {
    const bool relocalisation_tried = first.relocalisation_tried || first.suspect;
    h = step_hypothesis(std::move(h), prediction, relocalisation_tried, views);
  }
  if (!h.ok) register_lost(h.frame, scan, prediction);
  if (h.ok && h.step_rejected) register_refused_step(h, scan, prediction);
  commit(h, prediction, first, views, mapping_idle, keyframes_queued, outcome);
  frame = std::move(h.frame);
  if (outcome.new_map) return finish_initialised(frame, outcome);
  last_frame_ = frame;
  last_frame_->grid = FeatureGrid();
  return outcome;
}

Tracker::Prediction Tracker::predict(const Frame& frame) const {
  Prediction p;
  if (last_frame_) p.T_last_world = last_frame_->T_cam_world;
  p.T_cam_world = velocity_ ? *velocity_ * p.T_last_world : p.T_last_world;
  // Constant velocity over the time elapsed since the last frame, so that dropped frames (a gap in
  // the timestamps) move the guess as far as the camera went.
  if (velocity_ && last_frame_ && velocity_dt_ > 0.0) {
    const double steps = (frame.timestamp - last_frame_->timestamp) / velocity_dt_;
    if (std::isfinite(steps) && steps > 0.0) p.T_cam_world = se3_exp(steps * se3_log(*velocity_)) * p.T_last_world;
  }
  return p;
}

void Tracker::register_gap(const Frame& frame, PointCloudView scan, Prediction& prediction) const {
  if (!options_.register_gaps || !T_cam_lidar_ || !has_pose(state_) || !last_frame_ || !velocity_ ||
      !(velocity_dt_ > 0.0) || last_scan_.empty() || scan.empty()) {
    return;
  }
  const double dt = frame.timestamp - last_frame_->timestamp;
  if (!(dt > options_.gap_interval_ratio * velocity_dt_ && dt <= options_.max_gap_s)) return;
  const Stopwatch watch;
  prediction.gap = true;
  const auto g = register_across_gap(last_scan_, scan, *T_cam_lidar_,
                                     prediction.T_last_world * prediction.T_cam_world.inverse(), dt,
                                     options_.gap_registration, pool_.get());
  if (!g) {
    logger()->info("frame {}: {:.2f} s after the last frame: too little to register the scans across the gap",
                   frame.index, dt);
    return;
  }
  const ScanRegistration& r = g->registration;
  logger()->info("frame {}: {:.2f} s after the last frame, its scan registers onto the last one {:.2f} m, {:.2f} deg "
                 "from the constant-velocity guess (at most {:.2f} m, {:.2f} deg): agreement {:.3f} (runner-up "
                 "{:.3f}), probe loss {:.3f}, {} ({:.0f} ms)", frame.index, dt, g->moved_m, g->moved_deg, g->allowed_m,
                 g->allowed_deg, r.agreement, r.runner_up_agreement, r.min_probe_loss,
                 g->accepted ? "the prediction" : "not taken", watch.elapsed_ms());
  if (!g->accepted) return;
  prediction.T_cam_world = g->T_reference_query.inverse() * prediction.T_last_world;  // T_last_cur's inverse
  prediction.registered = true;
}

void Tracker::register_lost(const Frame& frame, PointCloudView scan, Prediction& prediction) const {
  // a gap frame's registration was tried already, from the same guess
  if (!options_.register_lost || prediction.gap) return;
  if (const auto T_cam_world = register_onto_last(frame, scan, prediction, "lost")) {
    prediction.T_cam_world = *T_cam_world;
    prediction.registered = true;
  }
}

bool Tracker::confirm_by_scan(Hypothesis& h, PointCloudView scan, Prediction& prediction, ViewLog& views) const {
  // Right after a tracked frame only: the registration measures the motion from the last frame, and
  // after a loss that frame's pose is itself a guess (a jump in the images, 04 frames 19 -> 35: the
  // frame after the lost one registers onto it within 0.04 m, 21 m from where the car is; its local
  // map was too thin to be kept there anyway, so this is a precaution, not a measured fix).
  if (!options_.confirm_suspect_by_scan || prediction.gap || !has_pose(state_) || !velocity_steady_ ||
      last_inliers_ <= 0) {
    return false;
  }
  const auto T_cam_world = register_onto_last(h.frame, scan, prediction, "motion model suspect");
  if (!T_cam_world) return false;
  // within a step's reach of the registration, as a step is judged against the prediction
  const double dt = h.frame.timestamp - last_frame_->timestamp;
  const Eigen::Vector3d last_centre = prediction.T_last_world.inverse().translation();
  const auto near = [&](const Frame& f) {
    return check_step(f.T_cam_world, *T_cam_world, last_centre, dt, options_).plausible;
  };
  if (near(h.frame)) return true;
  // The images' pose is off the scan's (a truck passing close pulls the motion model): the local map
  // searched from the registration, taken when it ends there on an ok frame's support.
  Search search = search_from(h.frame, *T_cam_world, h.reference, h.relocalisation_frame);
  const bool take = search.local.ok && near(search.frame);
  logger()->debug("frame {}: motion model suspect and off its scan's registration; from the registration the local "
                  "map finds {} of {}: {}", h.frame.index, search.local.inliers, search.local.visible,
                  take ? "taken" : "lost");
  if (!take) return false;
  h.reference = search.local.reference;
  settle(h, std::move(search), true, *T_cam_world, views);
  return true;
}

void Tracker::register_refused_step(Hypothesis& h, PointCloudView scan, Prediction& prediction) const {
  if (!options_.register_refused_steps || prediction.gap) return;
  if (const auto T_cam_world = register_onto_last(h.frame, scan, prediction, "its step refused")) {
    h.frame.T_cam_world = *T_cam_world;
    h.step_registered = true;
  }
}

std::optional<Eigen::Isometry3d> Tracker::register_onto_last(const Frame& frame, PointCloudView scan,
                                                             Prediction& prediction, const char* what) const {
  if (prediction.onto_last_tried) return prediction.onto_last;
  prediction.onto_last_tried = true;
  if (!T_cam_lidar_ || !last_frame_ || last_scan_.empty() || scan.empty()) return std::nullopt;
  const double dt = frame.timestamp - last_frame_->timestamp;
  if (!(dt > 0.0 && dt <= options_.max_gap_s)) return std::nullopt;
  const Stopwatch watch;
  const auto g = register_across_gap(last_scan_, scan, *T_cam_lidar_,
                                     prediction.T_last_world * prediction.T_cam_world.inverse(), dt,
                                     options_.gap_registration, pool_.get());
  if (!g) return std::nullopt;
  logger()->debug("frame {}: {}; its scan registers onto the last one {:.2f} m, {:.2f} deg from the "
                  "constant-velocity guess (at most {:.2f} m, {:.2f} deg): runner-up {:.3f} of {:.3f}, probe loss "
                  "{:.3f}, {} ({:.0f} ms)", frame.index, what, g->moved_m, g->moved_deg, g->allowed_m, g->allowed_deg,
                  g->registration.runner_up_agreement, g->registration.agreement, g->registration.min_probe_loss,
                  g->accepted ? "its pose" : "not taken", watch.elapsed_ms());
  if (!g->accepted) return std::nullopt;
  prediction.onto_last = g->T_reference_query.inverse() * prediction.T_last_world;  // T_last_cur's inverse
  return prediction.onto_last;
}

const char* Tracker::OtherStart::name() const {
  switch (source) {
    case Source::weak_consensus: return "weak depth consensus";
    case Source::second_motion: return "second rigid motion in view";
    case Source::road: return "road's own start";
    case Source::lidar: return "LiDAR's own start";
  }
  return "";
}

Tracker::FirstHypothesis Tracker::first_hypothesis(Frame frame, const Prediction& prediction, ViewLog& views) const {
  FirstHypothesis first;
  Hypothesis& h = first.hypothesis;
  h.reference = reference_;
  h.relocalisation_frame = last_relocalisation_frame_;
  bool ok = false;
  std::vector<OtherStart> others;  // more starts against the reference keyframe (see there)
  std::optional<LidarView> lidar;  // built when first needed
  if (has_pose(state_)) {
    if (prediction.registered) {
      // across a gap the LiDAR's registration is the guess and the motion's prior
      first.motion_inliers = track_with_motion_model(frame, *last_frame_, prediction.T_cam_world,
                                                     prediction.T_cam_world * prediction.T_last_world.inverse());
      ok = first.motion_ok = first.motion_inliers >= options_.min_pose_inliers;
    } else if (velocity_ && last_frame_) {
      first.motion_inliers =
          track_with_motion_model(frame, *last_frame_, *velocity_ * last_frame_->T_cam_world, trusted_velocity());
      ok = first.motion_ok = first.motion_inliers >= options_.min_pose_inliers;
    }
    if (!ok) {
      clear_matches(frame);
      ok = track_reference_keyframe(frame, others, lidar);
      if (!ok && !others.empty()) {
        frame = std::move(others.front().frame);  // the first other start that converged
        others.erase(others.begin());
        ok = true;
      }
    }
  } else {
    // Recently lost: the frame-to-frame motion (depth RANSAC + temporary points) usually still holds
    // and keeps the trajectory continuous; otherwise relocalise against the whole map.
    first.recent_loss = velocity_ && last_frame_ && frame.index <= last_ok_frame_ + options_.recent_loss_frames;
    if (first.recent_loss) {
      // Against the last tracked frame (the frames since carry only guesses and maybe no features,
      // e.g. black images), from the guess over the time elapsed.
      const Frame& reference = last_tracked_frame_ ? *last_tracked_frame_ : *last_frame_;
      first.motion_inliers = track_with_motion_model(frame, reference, prediction.T_cam_world, std::nullopt);
      ok = first.motion_ok = first.motion_inliers >= options_.min_pose_inliers;
      if (!ok) clear_matches(frame);
    }
    if (!ok) {
      ok = h.relocalised = relocalise(frame) && within_reach(frame, prediction);
      if (!ok) clear_matches(frame);
      // counts even if the local map rejects it below: the next frames need the stricter support
      if (ok) h.relocalisation_frame = frame.index;
    }
  }
  first.relocalisation_tried = state_ == TrackState::Lost && !first.motion_ok;
  if (ok) {
    const Frame after_motion = first.motion_ok ? frame : Frame{};
    const KeyframeId reference = h.reference;
    first.local = track_local_map(frame, reference, h.relocalisation_frame, views);
    h.reference = first.local.reference;
    const double dt = last_frame_ ? frame.timestamp - last_frame_->timestamp : 0.0;
    // A rival motion is judged as the depth consensus ranks motions: the road does not move, so the
    // start whose local map re-finds more points on the road wins, then the one that re-finds more.
    std::vector<bool> ground;
    if (!others.empty()) ground = ground_keypoints(camera_, frame, options_);
    auto on_road = [&](const Frame& f) {
      int count = 0;
      for (std::size_t i = 0; i < ground.size(); ++i) count += ground[i] && f.landmarks[i].valid() ? 1 : 0;
      return count;
    };
    for (OtherStart& other_start : others) {
      // starts converged to different poses: the local map decides. A rival motion's views count
      // only if it wins, so that a start that loses leaves the map's statistics as they were.
      ViewLog rival_views;
      ViewLog& other_views = other_start.rival() ? rival_views : views;
      const LocalMapResult other = track_local_map(other_start.frame, reference, h.relocalisation_frame, other_views);
      const int road = on_road(frame), other_road = on_road(other_start.frame);
      logger()->debug("frame {}: against the reference keyframe, the local map finds {} of {} points ({} on the road) "
                      "from the first start, {} of {} ({} on the road) from the {} ({:.2f} m apart)", frame.index,
                      first.local.inliers, first.local.visible, road, other.inliers, other.visible, other_road,
                      other_start.name(),
                      (frame.T_cam_world.inverse().translation() - other_start.frame.T_cam_world.inverse().translation()).norm());
      // Poses further apart than a vehicle's step tolerance are evidence that contradicts itself,
      // whichever wins: the frame is weak (and makes a keyframe), never silently ok. Two rigid
      // motions in view (the scene and a car) are not: each is a consensus of its own.
      const bool apart = !check_step(frame.T_cam_world, other_start.frame.T_cam_world, 0.0, dt, options_).plausible;
      if (apart && !other_start.rival()) h.weak = true;
      // The keypoints without depth first, where they are decisive; else the LiDAR, where it is (and the
      // start it picks holds on the local map); else the road, then the inliers. The LiDAR only between starts further apart than a step's
      // tolerance: its vote judges the motion from the last frame, whose own error is within that.
      // A rival within a step's tolerance of the first start is the same motion found twice.
      // To overrule the images the scans must be decisive with objects as the units: a start locked on
      // a truck alongside has the truck's hundreds of returns for it (traffic seed 3, frame 1: 205
      // returns against 75 for the scene, from two trucks).
      const int by_lidar = apart ? lidar_preference(lidar, frame, frame.T_cam_world, other_start.frame.T_cam_world,
                                                    "the first start", "the other", true)
                                 : 0;
      // The road's own start was drawn from the road: its road points are no evidence of their own, so it
      // must re-find more of the rest too (traffic seed 9, frame 1: a lane-line alias 1.3 m off found 22
      // points on the road against 14, and 187 in all against 369).
      const bool by_images = other_start.source == OtherStart::Source::road
                                 ? other_road > road && other.inliers > first.local.inliers
                                 : std::pair(other_road, other.inliers) > std::pair(road, first.local.inliers);
      // The keypoints without depth decide first where they clearly favour one start
      // (TrackerOptions::start_by_rays): they tell driving from standing and forward from backward, not
      // the scale. Traffic seed 41, frame 1: the paving and the LiDAR's flat facades took a start 0.2 m
      // backwards (the vehicles ahead pulling away); 104 of them fit the true 1.0 m step alone, 3 that.
      // Before the LiDAR's objects, which may be trucks at the ego speed: traffic seed 53, frame 1, they
      // chose standing still over the true 1.0 m decisively (z 3.14).
      int by_rays = 0;
      if (apart && other.ok && options_.start_by_rays) {
        const RayFits fits = fits_from_last(frame, frame.T_cam_world, other_start.frame.T_cam_world);
        by_rays = count_preference(fits.a_only, fits.b_only, 3.0);
        logger()->debug("frame {}: of {} matches of the last frame's keypoints without depth, {} fit the first start "
                        "alone, {} the other", frame.index, fits.matches, fits.a_only, fits.b_only);
      }
      const bool better = (apart || !other_start.rival()) &&
                          (by_rays != 0 ? by_rays > 0 : (by_lidar > 0 ? other.ok : by_lidar == 0 && by_images));
      // the scans overrule the images: the sensors contradict each other, the frame is never silently ok
      if (by_lidar != 0 && (by_lidar > 0) != by_images) h.weak = true;
      // Where the keypoints without depth overrule those with depth the frame stays ok: on every start
      // measured where they did, they were right (traffic seeds 7, 17, 41, 47), as session 21's weak
      // flag for a start chosen against clearly more inliers marked right starts (docs/accuracy.md).
      // It is reported, and the start's scale is left to the inliers (step_hypothesis).
      const bool rays_overrule = by_rays != 0 && (by_rays > 0) != by_images;
      if (better || rays_overrule) h.start_by_rays = rays_overrule;
      if (better) {
        frame = std::move(other_start.frame);
        first.local = other;
        h.reference = other.reference;
        views.visible.insert(views.visible.end(), rival_views.visible.begin(), rival_views.visible.end());
        views.found.insert(views.found.end(), rival_views.found.begin(), rival_views.found.end());
      }
    }
    ok = first.local.ok;
    if (ok && h.relocalised && !relocalisation_confirmed(first.local)) {
      logger()->debug("frame {}: relocalisation rejected, the local map re-finds {} of {} points", frame.index,
                      first.local.inliers, first.local.visible);
      ok = h.relocalised = false;
    }
    first.suspect = first.motion_ok && suspect(first.motion_inliers, first.local, frame.size());
    if (!ok && first.motion_ok && options_.keep_weak_tracking && !first.suspect) {
      // The map is thin here (e.g. mapping lags behind) but frame-to-frame motion held: keep the
      // motion-model pose and refresh the map with a keyframe instead of declaring the camera lost.
      frame = after_motion;
      frame.build_grid(camera_.width, camera_.height);
      ok = h.weak = true;
    }
    h.inliers = ok ? count_tracked(frame) : 0;
  }
  h.ok = ok;
  h.frame = std::move(frame);
  return first;
}

Tracker::Hypothesis Tracker::relocalisation_hypothesis(Frame frame, KeyframeId reference, ViewLog& views) const {
  Hypothesis h;
  h.reference = reference;
  h.relocalisation_frame = frame.index;
  clear_matches(frame);
  if (relocalise(frame)) {
    const LocalMapResult local = track_local_map(frame, reference, frame.index, views);
    h.reference = local.reference;
    h.ok = h.relocalised = local.ok && relocalisation_confirmed(local);
    h.inliers = h.ok ? count_tracked(frame) : 0;
  }
  h.frame = std::move(frame);
  return h;
}

const Tracker::LidarView* Tracker::lidar_view(std::optional<LidarView>& cache, const Frame& frame) const {
  if (!cache && options_.scan_arbitration && last_frame_ && last_frame_->scan && frame.scan) {
    cache.emplace(LidarView{ScanAgreement(*last_frame_->scan, options_.scan_sample.tolerance),
                            scan_evidence(*frame.scan, options_), {}});
  }
  return cache ? &*cache : nullptr;
}

bool Tracker::scans_prefer_prediction(std::optional<LidarView>& cache, const Frame& frame,
                                      const Eigen::Isometry3d& T_cam_world, const Prediction& prediction,
                                      const char* what) const {
  const double dt = frame.timestamp - last_frame_->timestamp;
  const Eigen::Vector3d last_centre = prediction.T_last_world.inverse().translation();
  if (check_step(T_cam_world, prediction.T_cam_world, last_centre, dt, options_).translation_plausible) return false;
  return lidar_preference(cache, frame, T_cam_world, prediction.T_cam_world, what, "the prediction", false) > 0;
}

bool Tracker::scans_refuse_relocalisation(const Hypothesis& relocalised, const Prediction& prediction) const {
  // A relocalisation is not checked as a step is (it may follow a loss), so the frame right after a
  // tracked one is judged here, under the step check's own conditions, by the vote step_hypothesis
  // asks of the relocalisation it tries. An image three frames old (04, frame 31 fed frame 28's) was
  // relocalised 4.2 m off on 161 inliers and reported ok.
  if (!options_.check_steps || !velocity_steady_ || !has_pose(state_) || !last_frame_ || prediction.registered) {
    return false;
  }
  std::optional<LidarView> lidar;
  return scans_prefer_prediction(lidar, relocalised.frame, relocalised.frame.T_cam_world, prediction,
                                 "the relocalisation");
}

int Tracker::lidar_preference(std::optional<LidarView>& cache, const Frame& frame, const Eigen::Isometry3d& T_a_world,
                              const Eigen::Isometry3d& T_b_world, const char* a, const char* b,
                              bool by_objects) const {
  if (lidar_view(cache, frame) == nullptr) return 0;
  LidarView& view = *cache;
  if (by_objects && view.objects.empty()) view.objects = label_objects(view.evidence, options_.scan_sample.tolerance);
  const Eigen::Isometry3d& T_last_world = last_frame_->T_cam_world;
  const ScanVote vote = view.last.vote(view.evidence, T_last_world * T_a_world.inverse(),
                                       T_last_world * T_b_world.inverse(),
                                       by_objects ? std::span<const std::uint32_t>(view.objects) : std::span<const std::uint32_t>());
  logger()->debug("frame {}: of {} LiDAR returns off the road, {} land on the last frame's scan only from {}, {} only "
                  "from {}{}", frame.index, view.evidence.points.size(), vote.only_a, a, vote.only_b, b,
                  by_objects ? fmt::format("; over objects, signed-rank z {:.2f}", vote.object_z) : std::string());
  return by_objects ? vote.object_preference() : vote.preference();
}

std::optional<Eigen::Isometry3d> Tracker::lidar_start(std::optional<LidarView>& cache, const Frame& frame) const {
  if (options_.lidar_start_max_speed <= 0.0) return std::nullopt;
  const Stopwatch watch;
  const LidarView* view = lidar_view(cache, frame);
  if (view == nullptr) return std::nullopt;
  const double dt = frame.timestamp - last_frame_->timestamp;
  // no further than the sample reaches: beyond that the scans share nothing (a gap in the frames)
  const double reach = std::min(options_.lidar_start_max_speed * (dt > 0.0 && std::isfinite(dt) ? dt : 0.1),
                                options_.scan_sample.max_range);
  // the search reads at most 1000 of the returns, spread over all of them; the vote then reads all
  ScanSample sparse;
  const std::size_t stride = view->evidence.points.size() / 1000 + 1;
  for (std::size_t i = 0; i < view->evidence.points.size(); i += stride) sparse.points.push_back(view->evidence.points[i]);
  // T_last_cur: the camera d metres further along the last one's z (no turn: a yaw searched here at
  // 0.25 deg steps came out 0.5 deg off on KITTI 04 at 1 Hz, and the local map refines the rotation)
  const auto ahead = [](double d) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().z() = d;
    return T;
  };
  double best = 0.0;
  std::size_t best_count = view->last.count(sparse, ahead(0.0));
  const auto search = [&](double from, double to, double step) {
    for (double d = from; d <= to + 1e-9; d += step) {
      const std::size_t c = view->last.count(sparse, ahead(d));
      if (c > best_count) {
        best_count = c;
        best = d;
      }
    }
  };
  search(-1.0, reach, 0.5);  // the agreement's peak is about 1.2 m wide at a 0.3 m tolerance
  search(best - 0.4, best + 0.4, 0.1);
  const ScanVote vote = view->last.vote(view->evidence, ahead(0.0), ahead(best));
  logger()->debug("frame {}: the LiDAR's start is {:.2f} m ahead; against standing still {} / {} of {} returns off "
                  "the road land on the last scan ({:.1f} ms)", frame.index, best, vote.only_b, vote.only_a,
                  view->evidence.points.size(), watch.elapsed_ms());
  if (vote.preference() <= 0) return std::nullopt;
  return ahead(best).inverse();
}

Tracker::Hypothesis Tracker::step_hypothesis(Hypothesis h, const Prediction& prediction, bool relocalisation_tried,
                                              ViewLog& views) const {
  // Never take silently a step that a vehicle cannot make. The local map is searched from the
  // prediction first: when it places the frame within a vehicle's reach on the support of an ok frame,
  // that pose wins over a step too far in translation, however many points agree on it (they are then
  // on something moving with the camera, e.g. a truck alongside at the ego speed); over a step off in
  // rotation alone only with more support. Else the step is taken on the evidence a relocalisation
  // needs (and reported as a jump), else the frame keeps the prediction.
  const double dt = h.frame.timestamp - last_frame_->timestamp;
  const Eigen::Vector3d last_centre = prediction.T_last_world.inverse().translation();
  const StepCheck step = check_step(h.frame.T_cam_world, prediction.T_cam_world, last_centre, dt, options_);
  if (step.plausible) {
    const std::optional<SpeedCheck> speed =
        check_speed(recent_, h.frame.timestamp, h.frame.T_cam_world.inverse().translation(), options_);
    if (!speed || speed->plausible) return h;
    return speed_hypothesis(std::move(h), prediction, *speed, views);
  }
  Search search = search_from(h.frame, prediction.T_cam_world, h.reference, h.relocalisation_frame);
  const Frame& candidate = search.frame;
  const LocalMapResult& from_prediction = search.local;
  const StepCheck candidate_step =
      check_step(candidate.T_cam_world, prediction.T_cam_world, last_centre, dt, options_);
  const bool plausible_alternative = from_prediction.ok && candidate_step.plausible;
  logger()->debug("frame {}: step {:.2f} m / {:.1f} deg off the prediction (allowed {:.2f} m; {:.2f} m short of "
                  "it, braking allows {:.2f} m) on {} inliers; from the prediction the local map finds {} ({:.2f} m "
                  "off)", h.frame.index, step.translation_m, step.rotation_deg, step.allowed_translation_m,
                  step.shortfall_m, step.allowed_shortfall_m, h.inliers, from_prediction.inliers,
                  candidate_step.translation_m);
  // A turn is judged on support: something moving in view shifts a pose locked on it by its own
  // displacement (metres at traffic speed) but cannot turn the whole scene, far points included; a
  // step off in rotation alone is the camera turning harder than constant velocity expects (a corner).
  const bool strongest =
      !plausible_alternative || (step.translation_plausible && h.inliers > from_prediction.inliers);
  // The LiDAR judges the motion from the last frame, and a step off the prediction is often the local
  // map correcting the last frames' error (lead-vehicle seed 3, frame 47: the step undid frame 46's
  // 0.9 deg and 0.3 m, and the LiDAR voted 1421 to 25 for keeping them); there the search from the
  // prediction ends at the step too. So it has a say only over a step beyond a vehicle's reach from
  // where that search ended as well: an image alias, e.g. a facade's windows, which repeat every bay
  // along the street, depth included, while the poles, trees and kerbs the scan sees do not. Asked
  // only for a step that would otherwise be taken: the vote reads the whole scan sample.
  std::optional<LidarView> lidar;  // built once, shared by the votes below
  const auto lidar_refuses = [&] {
    if (step.translation_plausible ||
        check_step(h.frame.T_cam_world, candidate.T_cam_world, last_centre, dt, options_).translation_plausible) {
      return false;
    }
    // Returns as the units here: refusing a step keeps the prediction, the safe side, and a facade
    // that repeats one bay along is itself one object voting for the alias (04 --first 3 --step 10,
    // frame 43: 1259 returns against 1099 for the prediction, undecided over objects).
    if (lidar_preference(lidar, h.frame, h.frame.T_cam_world, prediction.T_cam_world, "the step",
                         "the prediction", false) > 0) {
      return true;
    }
    // The search from the prediction ended beyond reach as well, elsewhere and nearer the prediction:
    // the images place the frame twice, apart. Where the scans clearly prefer the prediction to the
    // nearer of the two, the one further off is not taken on the images' word either (traffic seed
    // 57, frame 19, a truck and a bus filling the view: the step 0.77 m back on 144 inliers, 217
    // returns against 249; the search's pose 0.42 m back on 174, 123 against 179; truth ~0.55 m ahead).
    if (plausible_alternative || !from_prediction.ok || candidate_step.translation_m >= step.translation_m) {
      return false;
    }
    return lidar_preference(lidar, candidate, candidate.T_cam_world, prediction.T_cam_world, "the search's pose",
                            "the prediction", false) > 0;
  };
  if (strongest && h.inliers >= options_.min_jump_inliers && !h.weak && !lidar_refuses()) {
    h.jump = true;
    logger()->warn("frame {}: step {:.2f} m / {:.1f} deg off the constant-velocity prediction (allowed {:.2f} m), "
                   "taken on {} inliers", h.frame.index, step.translation_m, step.rotation_deg,
                   step.allowed_translation_m, h.inliers);
    return h;
  }
  if (!plausible_alternative && !relocalisation_tried) {
    // Neither the step nor the prediction can be taken: the frame is where a failed first hypothesis
    // would leave it, so relocalisation against the whole map, free of any prediction, is asked as it
    // is before a frame is declared lost, and taken on the same terms: when it explains more of the
    // frame. (A jump back into the mapped stretch: the local map, searched from a prediction 28 m off,
    // ends on a pose with 32 inliers; relocalisation places the frame on 179.)
    Hypothesis relocalised = relocalisation_hypothesis(h.frame, h.reference, views);
    // The relocalisation is a step too when it lands beyond a vehicle's reach: the scans that may have
    // just refused the step judge it as well (traffic seed 3 at nFeatures 1900 with the ring plane fit,
    // frame 54: the LiDAR voted 1010 to 238 against a 0.74 m step, then a relocalisation beside it on
    // 261 against 255 inliers was taken, and the map was lost six frames later).
    if (relocalised.ok && relocalised.inliers > h.inliers &&
        !scans_prefer_prediction(lidar, h.frame, relocalised.frame.T_cam_world, prediction, "the relocalisation")) {
      logger()->warn("frame {}: step {:.2f} m / {:.1f} deg off the constant-velocity prediction, taken as a "
                     "relocalisation on {} inliers", h.frame.index, step.translation_m, step.rotation_deg,
                     relocalised.inliers);
      return relocalised;
    }
  }
  // either way the frame is at (or near) the prediction: the local map searched there is its own
  const KeyframeId step_reference = h.reference;  // unless a start in doubt takes the step (below)
  h.reference = from_prediction.reference;
  // The prediction's pose is kept over a step beyond reach however many points agree on the step. Where
  // clearly more agree on the step than on that pose, though, the evidence contradicts the pose kept:
  // the frame is weak, never silently ok. Either side may be on vehicles: a truck alongside at the ego
  // speed, or a map locked on the trucks since its start (traffic seed 13, frames 5-7: 286-303
  // inliers on the true 1.0 m steps against 196-221 at the prediction, standing still). Clearly: by
  // two sigmas of the counts' difference, each count taken as Poisson (sigma sqrt(a + b)); a few
  // inliers either way are a tie (traffic seed 3 at the lights: 252 against 246).
  h.step_contested = plausible_alternative && clearly_more(h.inliers, from_prediction.inliers);
  if (h.step_contested) {
    logger()->debug("frame {}: kept at the prediction on {} inliers against a step with {}: weak", h.frame.index,
                    from_prediction.inliers, h.inliers);
  }
  // A start's velocity is in doubt for its first moments (TrackerOptions::start_doubt_s): the
  // keypoints without depth, the scene beyond the LiDAR's reach that vehicles around the car rarely
  // hold, decide a contested step there. Traffic seed 13 starts standing among trucks at its speed and
  // at frame 5 (0.4 s) 57 of them fit the true 1.0 m step alone, 5 the prediction; seed 22, started
  // right, has its steps contested by the trucks at frames 4-7 and 1-3 fit those alone, 7-20 the prediction.
  // A start the rays chose against the depth's evidence has a direction but no checked scale, and the
  // rays cannot judge a scale (a longer step's rays cover a shorter one's): there the inliers decide,
  // and the rays only object (traffic seed 13 at nFeatures 2200: the rays took the oncoming lanes'
  // 2.27 m over the trucks' standing still, truth 1.0 m; at frame 6 the true step has 316 inliers
  // against 192, the rays 14 against 2, short of three sigmas).
  if (h.step_contested && start_ && h.frame.timestamp - start_->time <= options_.start_doubt_s) {
    const RayFits fits = fits_from_last(h.frame, h.frame.T_cam_world, prediction.T_cam_world);  // a: the step
    const int by_rays = count_preference(fits.a_only, fits.b_only, 3.0);
    const bool take = start_->by_rays ? by_rays <= 0 : by_rays < 0;
    logger()->log(take ? spdlog::level::warn : spdlog::level::debug,
                  "frame {}: {:.2f} s after a start without velocity, the keypoints without depth fit the contested "
                  "step alone {} times, the prediction alone {}: {}", h.frame.index,
                  h.frame.timestamp - start_->time, fits.a_only, fits.b_only,
                  take ? "the step is taken (the start was wrong)" : "kept at the prediction");
    if (take) {
      h.jump = true;  // reported as a step beyond a vehicle's reach, and weak (contested)
      h.start_refuted = true;
      h.reference = step_reference;
      return h;
    }
  }
  settle(h, std::move(search), plausible_alternative, prediction.T_cam_world, views);
  return h;
}

Tracker::Hypothesis Tracker::speed_hypothesis(Hypothesis h, const Prediction& prediction, const SpeedCheck& speed,
                                               ViewLog& views) const {
  // the prediction's rotation, the centre where the speed puts it
  Search search = search_from(h.frame, pose_at_centre(prediction.T_cam_world.linear(), speed.expected_centre),
                              h.reference, h.relocalisation_frame);
  const LocalMapResult& from_speed = search.local;
  const Eigen::Vector3d found_centre = search.frame.T_cam_world.inverse().translation();
  RayFits fits;
  bool take = from_speed.ok && speed.reaches(found_centre);
  if (take) {
    // Either may be on vehicles: the speed's pose decides only where the keypoints without depth, the
    // scene beyond the LiDAR's reach, fit it clearly more often than the step (a: the step). Both
    // at the step's rotation: the question is the speed, and the far points, which fit one rotation
    // only, would decide it by the rotation (traffic seed 22 at nFeatures 2100, frame 7: 21 against
    // 11 at their own rotations; frame 8 at one rotation: 1 against 73).
    fits = fits_from_last(h.frame, h.frame.T_cam_world, pose_at_centre(h.frame.T_cam_world.linear(), found_centre));
    take = count_preference(fits.a_only, fits.b_only, 3.0) > 0;
  }
  logger()->log(take ? spdlog::level::warn : spdlog::level::debug,
                "frame {}: {:.2f} m from where the speed over the {:.2f} s before frame {} puts it (allowed {:.2f} m, "
                "{:.1f} m/s) on {} inliers; from there the local map finds {} ({:.2f} m off); the keypoints without "
                "depth fit the step alone {} times, that pose alone {}: {}",
                h.frame.index, speed.deviation_m, options_.speed_window_s, h.frame.index - speed.frames_back,
                speed.allowed_m, speed.velocity.norm(), h.inliers, from_speed.inliers,
                (found_centre - speed.expected_centre).norm(), fits.a_only, fits.b_only,
                take ? "taken" : "the step kept");
  if (!take) return h;
  h.reference = from_speed.reference;
  h.speed_placed = speed.velocity;
  // clearly more inliers on the step than where the speed puts the frame: weak, as a contested step
  h.step_contested = clearly_more(h.inliers, from_speed.inliers);
  settle(h, std::move(search), true, prediction.T_cam_world, views);
  return h;
}

RayFits Tracker::fits_from_last(const Frame& frame, const Eigen::Isometry3d& T_a_world,
                                const Eigen::Isometry3d& T_b_world) const {
  const Eigen::Isometry3d T_world_last = last_frame_->T_cam_world.inverse();
  return fits_by_rays(camera_, *last_frame_, frame, T_a_world * T_world_last, T_b_world * T_world_last,
                      options_.motion_max_hamming, map_.options().scale_factor);
}

Tracker::Search Tracker::search_from(const Frame& frame, const Eigen::Isometry3d& T_cam_world, KeyframeId reference,
                                     std::size_t relocalisation_frame) const {
  Search s{frame, {}, {}};
  s.frame.T_cam_world = T_cam_world;
  clear_matches(s.frame);
  s.local = track_local_map(s.frame, reference, relocalisation_frame, s.views);
  return s;
}

void Tracker::settle(Hypothesis& h, Search search, bool take, const Eigen::Isometry3d& T_cam_world, ViewLog& views) {
  views.visible.insert(views.visible.end(), search.views.visible.begin(), search.views.visible.end());
  views.found.insert(views.found.end(), search.views.found.begin(), search.views.found.end());
  if (take) {
    h.frame = std::move(search.frame);
    h.inliers = count_tracked(h.frame);
    h.weak = false;
  } else {
    h.frame.T_cam_world = T_cam_world;
    clear_matches(h.frame);
    h.inliers = 0;
    h.weak = h.step_rejected = true;
  }
}

Tracker::Hypothesis Tracker::gap_hypothesis(Hypothesis h, const Prediction& prediction, ViewLog& views) const {
  // check_step without an allowance: the centres' distance and the rotation between the poses
  const auto off = [&](const Eigen::Isometry3d& T_cam_world) {
    return check_step(T_cam_world, prediction.T_cam_world, 0.0, 0.0, options_);
  };
  const auto within = [&](const StepCheck& c) {
    return c.translation_m <= options_.gap_tolerance_m && c.rotation_deg <= options_.gap_tolerance_deg;
  };
  const StepCheck taken = off(h.frame.T_cam_world);
  if (within(taken)) return h;
  Search search = search_from(h.frame, prediction.T_cam_world, h.reference, last_relocalisation_frame_);
  const LocalMapResult& local = search.local;
  const bool agrees = local.ok && within(off(search.frame.T_cam_world));
  logger()->warn("frame {}: {}placed {:.2f} m / {:.1f} deg from the scans' registration across the gap (at most "
                 "{:.2f} m / {:.1f} deg) on {} inliers; from the registration the local map finds {} of {}: {}",
                 h.frame.index, h.relocalised ? "relocalised, " : "", taken.translation_m, taken.rotation_deg,
                 options_.gap_tolerance_m,
                 options_.gap_tolerance_deg, h.inliers, local.inliers, local.visible,
                 agrees ? "taken" : "weak, at the registration");
  h.reference = local.reference;
  h.relocalised = false;
  h.relocalisation_frame = last_relocalisation_frame_;
  settle(h, std::move(search), agrees, prediction.T_cam_world, views);
  return h;
}

void Tracker::commit(Hypothesis& h, const Prediction& prediction, const FirstHypothesis& first, const ViewLog& views,
                     bool mapping_idle, std::size_t keyframes_queued, TrackerOutcome& outcome) {
  {
    std::unique_lock lock(map_.mutex());
    for (const LandmarkId id : views.visible) {
      if (Landmark* l = map_.landmark(id)) ++l->visible;
    }
    for (const LandmarkId id : views.found) {
      if (Landmark* l = map_.landmark(id)) ++l->found;
    }
    for (const LandmarkId id : h.frame.moved_landmarks) {
      if (map_.landmark(id) != nullptr) map_.erase_landmark(id);
    }
  }
  const TrackState previous_state = state_;
  Frame& frame = h.frame;
  reference_ = h.reference;
  last_relocalisation_frame_ = h.relocalisation_frame;
  outcome.relocalised = h.relocalised;
  outcome.jump = h.jump;
  outcome.step_rejected = h.step_rejected;
  outcome.step_registered = h.step_registered;
  outcome.step_contested = h.step_contested;
  if (h.start_refuted) outcome.start_refuted_since = start_->frame;
  outcome.speed_corrected = h.speed_placed.has_value();
  outcome.start_by_rays = h.start_by_rays;
  outcome.scan_confirmed = h.scan_confirmed;
  outcome.gap = prediction.gap;
  outcome.gap_registered = prediction.registered;
  int inliers = h.inliers;
  if (h.ok) {
    const bool consecutive = has_pose(state_);  // the previous frame was tracked too
    state_ = h.weak || h.step_contested ? TrackState::Weak
                                   : support_state(inliers, frames_since_relocalisation(frame), options_);
    last_ok_frame_ = frame.index;
    last_inliers_ = inliers;
    // a refused step placed at the prediction keeps the velocity; placed by its scan, the scans
    // measured the motion where the images could not, and it becomes the velocity
    if (last_frame_ && (!h.step_rejected || h.step_registered)) {
      velocity_dt_ = frame.timestamp - last_frame_->timestamp;
      // placed by the speed over a window: the step from the last frame carries that frame's error,
      // so the last frame is taken where the window's speed puts it
      const Eigen::Isometry3d T_last_world =
          h.speed_placed ? pose_at_centre(last_frame_->T_cam_world.linear(),
                                          frame.T_cam_world.inverse().translation() - *h.speed_placed * velocity_dt_)
                         : last_frame_->T_cam_world;
      velocity_ = frame.T_cam_world * T_last_world.inverse();
    }
    const PlacedCentre placed{frame.timestamp, frame.T_cam_world.inverse().translation()};
    if (consecutive && !h.relocalised && !h.jump && !prediction.gap) {
      recent_.push_back(placed);
      // what check_speed reads: two windows back, and a frame more
      const auto stale = std::find_if(recent_.begin(), recent_.end(), [&](const PlacedCentre& p) {
        return frame.timestamp - p.time <= 2.5 * options_.speed_window_s;
      });
      if (stale - recent_.begin() > 1) recent_.erase(recent_.begin(), stale - 1);
    } else {
      recent_.assign(1, placed);
    }
    // a velocity set without a steady one before it stands on this frame's start alone
    if (!velocity_steady_ && !h.step_rejected) start_ = Start{frame.timestamp, frame.index, h.start_by_rays};
    if (last_frame_ && !h.step_rejected) {
      // A velocity from two consecutive tracked frames is steady however the second was placed: one
      // placed against the reference keyframe (the frame after a map's first, which has no velocity)
      // was chosen among the starts by the local map and the scans, and the next frame's depth
      // RANSAC without it as a prior, and with no step check, takes the largest consensus, the trucks
      // alongside at the ego speed (traffic seed 27, frame 2: 1.0 m tracked at frame 1, 0.04 m at
      // frame 2, and standing still for the rest of the run, 7.5 m off).
      velocity_steady_ = consecutive && !h.relocalised;
      if (consecutive && !h.relocalised && !h.jump && !h.speed_placed) travel_.add(last_frame_->T_cam_world, frame.T_cam_world, options_);
    }
    // a frame placed at the prediction has no observations worth a keyframe; a full mapping queue
    // takes none (those waiting refresh the map soon)
    outcome.need_keyframe = !h.step_rejected &&
                            keyframes_queued < static_cast<std::size_t>(options_.max_queued_keyframes) &&
                            (h.weak || need_keyframe(frame, inliers, mapping_idle));
  } else {
    const bool was_lost = state_ == TrackState::Lost;
    logger()->debug("frame {}: lost: frame-to-frame motion {} inliers ({} needed), local map {} of {} points in view "
                    "({} needed){}{}", frame.index, first.motion_inliers, options_.min_pose_inliers, first.local.inliers,
                    first.local.visible, options_.min_ok_inliers, first.suspect ? ", motion model suspect" : "",
                    first.relocalisation_tried || !first.motion_ok ? ", no relocalisation in the map" : "");
    state_ = TrackState::Lost;
    velocity_steady_ = false;
    recent_.clear();
    inliers = 0;
    last_inliers_ = 0;
    frame.T_cam_world = prediction.T_cam_world;  // best guess, reported with state Lost
    clear_matches(frame);
    if (options_.register_lost && prediction.registered && last_frame_) {
      // the scans measured this motion, the images did not contradict it: the velocity from here on
      velocity_ = frame.T_cam_world * last_frame_->T_cam_world.inverse();
      velocity_dt_ = frame.timestamp - last_frame_->timestamp;
      outcome.lost_registered = true;
    }
    // Lost beyond the recent-loss window and the map does not know this place: carry on in a new map
    // anchored at the lost pose (as ORB-SLAM3's atlas) rather than staying lost until the camera returns.
    // At once where the scans placed the frame and too little of the map is in view from there for an
    // ok frame (min_ok_inliers; after a gap of seconds the map lies behind the car): waiting for the
    // motion model cannot bring the frames back onto this map.
    const bool window_over = was_lost && !first.recent_loss;
    const int in_view = options_.new_map_when_lost && !window_over && outcome.lost_registered
                            ? landmarks_in_view(prediction.T_cam_world, reference_)
                            : -1;
    const bool map_behind = in_view >= 0 && in_view < options_.min_ok_inliers;
    if ((window_over || map_behind) && options_.new_map_when_lost && initialise(frame, prediction.T_cam_world)) {
      if (map_behind) {
        logger()->warn("frame {}: {} of the map's points in view at the scans' pose (an ok frame needs {}): new map "
                       "started there", frame.index, in_view, options_.min_ok_inliers);
      } else {
        logger()->warn("frame {}: lost since frame {} and relocalisation failed: new map started at the {}",
                       frame.index, last_ok_frame_, outcome.lost_registered ? "scans' pose" : "constant-velocity guess");
      }
      outcome.new_map = true;
      return;
    }
  }
  outcome.state = state_;
  outcome.inliers = inliers;
  if (has_pose(state_)) {
    last_tracked_frame_.reset();
  } else if (has_pose(previous_state) && last_frame_) {
    last_tracked_frame_ = std::move(last_frame_);  // the first lost frame: keep the last tracked one
  }
}

TrackerOutcome& Tracker::finish_initialised(const Frame& frame, TrackerOutcome& outcome) {
  state_ = TrackState::Ok;
  outcome.initialised_now = true;
  outcome.inliers = count_tracked(frame);
  last_ok_frame_ = frame.index;
  last_inliers_ = 0;  // every depth point is a landmark here: no yardstick for the next frame
  outcome.state = state_;
  last_frame_ = frame;
  last_frame_->grid = FeatureGrid();
  last_tracked_frame_.reset();
  recent_.assign(1, PlacedCentre{frame.timestamp, frame.T_cam_world.inverse().translation()});
  return outcome;
}

bool Tracker::suspect(int motion_inliers, const LocalMapResult& local, std::size_t keypoints) const {
  return motion_suspect({.motion_inliers = motion_inliers,
                         .last_inliers = last_inliers_,
                         .keypoints = keypoints,
                         .last_keypoints = last_frame_ ? last_frame_->size() : 0,
                         .local_inliers = local.inliers,
                         .local_visible = local.visible},
                        options_);
}

bool Tracker::within_reach(const Frame& frame, const Prediction& prediction) const {
  // The camera cannot be anywhere: from the last tracked pose and velocity, over the time since, it is
  // within the step check's reach of the constant-velocity guess (the allowance grows with the time
  // squared, so after a few seconds anywhere goes). A straight road looks alike along itself: KITTI 04
  // at 1.2 Hz relocalised a frame after one lost frame at the last tracked frame's place, 21.7 m short,
  // where braking at 1 g from 13 m/s still covers 8.5 m; the local map re-found 89 of 717 points there.
  if (!options_.check_steps || !velocity_ || !last_tracked_frame_) return true;
  const double dt = frame.timestamp - last_tracked_frame_->timestamp;
  if (!(dt > 0.0) || !std::isfinite(dt)) return true;
  const StepCheck reach = check_step(frame.T_cam_world, prediction.T_cam_world,
                                     last_tracked_frame_->T_cam_world.inverse().translation(), dt, options_);
  if (reach.translation_plausible) return true;
  logger()->debug("frame {}: relocalisation rejected, {:.2f} m from the constant-velocity guess {:.2f} s after the last "
                  "tracked frame (within reach: {:.2f} m), {:.2f} m short of it (braking allows {:.2f} m)", frame.index,
                  reach.translation_m, dt, reach.allowed_translation_m, reach.shortfall_m, reach.allowed_shortfall_m);
  return false;
}

bool Tracker::relocalisation_confirmed(const LocalMapResult& local) const {
  const double needed = options_.relocalisation_min_found_ratio * local.visible;
  return needed < options_.min_pose_inliers || local.inliers >= needed;  // judged as suspect() judges
}

bool Tracker::initialise(Frame& frame, const Eigen::Isometry3d& T_cam_world) {
  const int usable = static_cast<int>(std::count_if(frame.depth_sigma.begin(), frame.depth_sigma.end(),
                                                    [](float s) { return s > 0.0F; }));
  if (usable < options_.min_initial_depth_points) {
    logger()->debug("frame {}: not initialised: {} keypoints with usable depth, {} needed "
                    "(tracker.min_initial_depth_points)", frame.index, usable, options_.min_initial_depth_points);
    return false;
  }
  frame.T_cam_world = T_cam_world;
  std::unique_lock lock(map_.mutex());
  const KeyframeId id = map_.add_keyframe(keyframe_from(frame, options_));
  const Eigen::Isometry3d T_world_cam = frame.T_cam_world.inverse();
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.depth_sigma[i] <= 0.0F) continue;
    const Eigen::Vector3d p = camera_.unproject(Eigen::Vector2d(frame.keypoints[i].x, frame.keypoints[i].y),
                                                frame.depth[i]);
    const LandmarkId l = map_.add_landmark(T_world_cam * p, id);
    map_.add_observation(l, id, static_cast<int>(i));
    map_.update_landmark(l);
    frame.landmarks[i] = l;
  }
  reference_ = id;
  last_keyframe_frame_ = frame.index;
  return true;
}

std::optional<PoseMotionPrior> Tracker::motion_prior() const {
  if (!options_.direction_prior || !last_frame_ || !has_pose(state_)) return std::nullopt;
  const std::optional<Eigen::Vector3d> direction = travel_.direction(options_);
  if (!direction) return std::nullopt;
  PoseMotionPrior prior;
  prior.T_last_world = last_frame_->T_cam_world;
  prior.direction_cam = *direction;
  prior.sigmas = options_.direction_prior_sigmas;
  return prior;
}

int Tracker::optimise_pose(Frame& frame, const std::vector<std::pair<std::size_t, Eigen::Vector3d>>& extra,
                           bool relocalising) const {
  std::vector<PoseObservation> observations;
  std::vector<std::size_t> keypoint_of;
  observations.reserve(frame.size());
  // Keypoint i seeing p_world, with its LiDAR depth where that is close enough to constrain the pose.
  auto add = [&](std::size_t i, const Eigen::Vector3d& p_world) {
    PoseObservation o;
    o.p_world = p_world;
    o.pixel = Eigen::Vector2d(frame.keypoints[i].x, frame.keypoints[i].y);
    o.sigma_px = level_scale(map_, frame.keypoints[i].level);
    if (frame.depth_sigma[i] > 0.0F && frame.depth[i] < options_.close_depth) {
      o.depth = frame.depth[i];
      o.depth_sigma = frame.depth_sigma[i];
    }
    observations.push_back(o);
    keypoint_of.push_back(i);
  };
  {
    std::shared_lock lock(map_.mutex());
    for (std::size_t i = 0; i < frame.size(); ++i) {
      const Landmark* l = frame.landmarks[i].valid() ? map_.landmark(frame.landmarks[i]) : nullptr;
      if (l == nullptr) {
        frame.landmarks[i] = LandmarkId{};
        continue;
      }
      add(i, l->position);
    }
  }
  for (const auto& [i, p_world] : extra) add(i, p_world);
  if (observations.size() < static_cast<std::size_t>(options_.min_pose_inliers)) return 0;
  const std::optional<PoseMotionPrior> prior = relocalising ? std::nullopt : motion_prior();
  PoseOptimizerResult result = optimize_pose(camera_, frame.T_cam_world, observations, options_.pose, prior);
  if (options_.object_test && result.inliers >= options_.min_pose_inliers &&
      leave_out_erring_objects(frame, observations, keypoint_of, result.T_cam_world, result.inlier)) {
    result = optimize_pose(camera_, result.T_cam_world, observations, options_.pose, prior);
  }
  frame.T_cam_world = result.T_cam_world;
  for (std::size_t j = 0; j < observations.size(); ++j) frame.outlier[keypoint_of[j]] = !result.inlier[j];
  return result.inliers;
}

bool Tracker::leave_out_erring_objects(Frame& frame, std::vector<PoseObservation>& observations,
                                       std::vector<std::size_t>& keypoint_of, const Eigen::Isometry3d& T_cam_world,
                                       const std::vector<bool>& inlier) const {
  // the road does not move: its points are no object
  std::vector<Eigen::Vector3d> measured;
  std::vector<std::size_t> measured_of;
  for (std::size_t j = 0; j < observations.size(); ++j) {
    if (!inlier[j] || observations[j].depth <= 0.0) continue;
    measured.push_back(camera_.unproject(observations[j].pixel, observations[j].depth));
    measured_of.push_back(j);
  }
  const std::vector<bool> on_ground = ground_points(measured, options_);
  std::vector<bool> road(observations.size(), false);
  for (std::size_t m = 0; m < on_ground.size(); ++m) road[measured_of[m]] = on_ground[m];
  const ObjectGrouping grouping{options_.moving_label_radius, options_.ransac_min_tolerance,
                                options_.ransac_relative_tolerance};
  const ObjectResiduals objects = objects_against_pose(camera_, T_cam_world, observations, inlier, road, grouping,
                                                       options_.object_residuals, options_.pose.bounded_depth_error);
  if (objects.flagged_objects == 0) return false;
  std::vector<PoseObservation> kept;
  std::vector<std::size_t> kept_of;
  if (frame.moving.empty()) frame.moving.assign(frame.size(), false);
  for (std::size_t j = 0; j < observations.size(); ++j) {
    const std::size_t k = keypoint_of[j];
    if (!objects.flagged[j]) {
      kept.push_back(observations[j]);
      kept_of.push_back(k);
      continue;
    }
    if (frame.landmarks[k].valid()) frame.moved_landmarks.push_back(frame.landmarks[k]);
    frame.moving[k] = true;
    frame.outlier[k] = true;
  }
  logger()->debug("frame {}: {} of {} objects err together ({} points, overdispersion {:.2f})", frame.index,
                  objects.flagged_objects, objects.objects, observations.size() - kept.size(), objects.overdispersion);
  observations = std::move(kept);
  keypoint_of = std::move(kept_of);
  return true;
}

int Tracker::track_with_motion_model(Frame& frame, const Frame& reference, const Eigen::Isometry3d& T_guess,
                                     const std::optional<Eigen::Isometry3d>& prior) const {
  frame.T_cam_world = T_guess;
  bool from_consensus = false;
  if (options_.ransac_prediction) {
    if (const auto T_cur_last = estimate_frame_motion(camera_, reference, frame, options_, prior, &frame.moving)) {
      frame.T_cam_world = *T_cur_last * reference.T_cam_world;
      from_consensus = true;
    }
  }
  std::vector<detail::ProjectedLandmark> candidates;
  std::vector<Eigen::Vector3d> candidate_points;
  const Eigen::Isometry3d T_world_last = reference.T_cam_world.inverse();
  auto build = [&](double radius_factor) {
    candidates.clear();
    candidate_points.clear();
    std::shared_lock lock(map_.mutex());
    const Frame& last = reference;
    for (std::size_t i = 0; i < last.size(); ++i) {
      const bool landmark = last.landmarks[i].valid() && !last.outlier[i];
      const Landmark* l = landmark ? map_.landmark(last.landmarks[i]) : nullptr;
      // Keypoints of the last frame with depth but no landmark become temporary points (ORB-SLAM's
      // visual-odometry points): they anchor frame-to-frame motion where the map is thin.
      const bool temporary = l == nullptr && last.depth_sigma[i] > 0.0F && options_.temporary_points && !last.is_moving(i);
      if (l == nullptr && !temporary) continue;
      const Eigen::Vector3d p_world =
          l != nullptr ? l->position
                       : T_world_last * camera_.unproject(Eigen::Vector2d(last.keypoints[i].x, last.keypoints[i].y),
                                                          last.depth[i]);
      const Eigen::Vector3d p = frame.T_cam_world * p_world;
      if (p.z() <= 0.0) continue;
      const Eigen::Vector2d px = camera_.project_unchecked(p);
      if (!camera_.in_image(px)) continue;
      const int level = last.keypoints[i].level;
      detail::ProjectedLandmark c;
      if (l != nullptr) c.id = l->id;
      c.descriptor = l != nullptr ? l->descriptor : last.descriptors[i];
      c.x = static_cast<float>(px.x());
      c.y = static_cast<float>(px.y());
      c.radius = static_cast<float>(radius_factor * level_scale(map_, level));
      candidate_points.push_back(p_world);
      c.min_level = std::max(0, level - 1);
      c.max_level = level + 1;
      c.angle = last.keypoints[i].angle;
      c.depth = static_cast<float>(p.z());
      candidates.push_back(c);
    }
  };
  std::vector<int> candidate_of_keypoint;
  const detail::DepthGate gate{static_cast<float>(options_.depth_gate_sigmas),
                               static_cast<float>(options_.depth_gate_min_motion)};
  build(options_.motion_radius);
  int matches = detail::match_projected(frame, candidates, options_.motion_max_hamming, options_.motion_ratio, options_.check_orientation,
                                        &candidate_of_keypoint, gate);
  if (matches < options_.motion_min_matches) {
    clear_matches(frame);
    build(2.0 * options_.motion_radius);
    matches = detail::match_projected(frame, candidates, options_.motion_max_hamming, options_.motion_ratio, options_.check_orientation,
                                      &candidate_of_keypoint, gate);
  }
  if (matches < options_.motion_min_matches) return 0;
  // The depth consensus predicts the pose well: matches far from it are on objects moving against the
  // scene and are left out of the pose (the constant-velocity guess alone is not trusted that far).
  // Without a consensus, a trusted constant velocity predicts the pose to within a vehicle's reach
  // (the step check's tolerance), which widens the gate by as much.
  const bool moving_gate = (from_consensus || prior) && options_.motion_gate_factor > 0.0;
  const double slack = from_consensus || !prior ? 0.0 : allowed_step(prior->translation().norm(), velocity_dt_, options_);
  if (moving_gate) drop_moving_matches(frame, slack);
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> extra;
  for (std::size_t k = 0; k < frame.size(); ++k) {
    const int c = candidate_of_keypoint[k];
    if (c >= 0 && !candidates[static_cast<std::size_t>(c)].id.valid()) {
      const Eigen::Vector3d& p_world = candidate_points[static_cast<std::size_t>(c)];
      if (!moving_gate || !disagrees_with_pose(frame, k, p_world, slack)) extra.emplace_back(k, p_world);
    }
  }
  const int inliers = optimise_pose(frame, extra);
  discard_outliers(frame);
  return inliers;
}

bool Tracker::track_reference_keyframe(Frame& frame, std::vector<OtherStart>& others,
                                       std::optional<LidarView>& lidar) const {
  others.clear();
  std::vector<Descriptor> train;
  std::vector<LandmarkId> train_landmarks;
  {
    std::shared_lock lock(map_.mutex());
    const Keyframe* kf = map_.keyframe(reference_);
    if (kf == nullptr) kf = map_.keyframe(map_.last_keyframe_id());
    if (kf == nullptr) return false;
    for (std::size_t i = 0; i < kf->keypoints.size(); ++i) {
      if (!kf->landmarks[i].valid()) continue;
      train.push_back(kf->descriptors[i]);
      train_landmarks.push_back(kf->landmarks[i]);
    }
  }
  const auto matches =
      detail::match_brute_force(frame.descriptors, train, options_.max_hamming, options_.reference_ratio);
  if (static_cast<int>(matches.size()) < options_.reference_min_matches) return false;
  for (const auto& [q, t] : matches) frame.landmarks[static_cast<std::size_t>(q)] = train_landmarks[static_cast<std::size_t>(t)];
  const std::optional<Eigen::Isometry3d> T_lidar = lidar_start(lidar, frame);
  // Start from the frame-to-frame motion from depth where its consensus is strong (the frame right
  // after initialisation has no velocity yet, and the last pose is then a poor guess at speed), else
  // from the last pose, and then also from the weak consensus: far off at speed, the last pose can
  // converge on distant points to a wrong pose that many matches fit (KITTI 04 at 2.5 Hz: 5 m short).
  // Without a velocity the largest rigid consensus may also be a car moving with the camera, or
  // aliasing, while the scene's matches fade with the distance travelled (KITTI 04 at 1.7 Hz: 20
  // points on a 2 m sideways motion, 7 on the true 7.9 m one): the second rigid motion among the
  // matches is another start. The local map decides between the starts.
  frame.T_cam_world = last_frame_ ? last_frame_->T_cam_world : Eigen::Isometry3d::Identity();
  auto start_from = [&](Frame& f, const Eigen::Isometry3d& T_cur_last) {
    f.T_cam_world = T_cur_last * last_frame_->T_cam_world;
    // Descriptor matches carry no geometry: those whose 3-D point disagrees with the static
    // consensus are objects moving against the scene (or aliasing), not evidence for the pose.
    drop_moving_matches(f);
  };
  // the road's and the LiDAR's starts: at their pose without matches (OtherStart::as_proposed)
  auto add_as_proposed = [&](OtherStart::Source source, const Eigen::Isometry3d& T_cur_last) {
    OtherStart& other = others.emplace_back(OtherStart{frame, source});
    clear_matches(other.frame);
    other.frame.T_cam_world = T_cur_last * last_frame_->T_cam_world;
  };
  auto add_rival = [&](const Frame& matched, std::optional<RivalMotion>& rival) {
    if (!rival) return;
    OtherStart& other = others.emplace_back(OtherStart{matched, OtherStart::Source::second_motion});
    other.frame.moving = std::move(rival->moving);
    start_from(other.frame, rival->T_cur_last);
  };
  if (last_frame_ && options_.ransac_prediction) {
    TrackerOptions guess_options = options_;  // a guess only: the optimisation below decides
    guess_options.ransac_min_inliers = options_.ransac_guess_min_inliers;
    std::optional<RivalMotion> rival;
    if (const auto T_cur_last = estimate_frame_motion(camera_, *last_frame_, frame, guess_options, trusted_velocity(),
                                                      &frame.moving, &rival)) {
      add_rival(frame, rival);
      start_from(frame, *T_cur_last);
    } else {
      Frame weak = frame;
      guess_options.ransac_min_inliers = 3;  // any consensus; the same sampling finds the same motion
      if (const auto T_weak = estimate_frame_motion(camera_, *last_frame_, weak, guess_options, trusted_velocity(),
                                                    &weak.moving, &rival)) {
        add_rival(frame, rival);
        start_from(weak, *T_weak);
        others.insert(others.begin(), OtherStart{std::move(weak), OtherStart::Source::weak_consensus});
      }
    }
  }
  if (T_lidar) {
    // A rival: its views count only if it wins. It stands on the scans, not on the brute-force
    // matches: at 1 Hz those hold few right ones, and where a vehicle alongside moves with the camera
    // they hold its points, which the gate does not drop far ahead (6 % of the depth is more than the
    // step at 25 m), and which pulled the LiDAR's start back onto the standing start (traffic seed 7,
    // frame 1: 1.10 m ahead, optimised to 0.05 m from standing still, the truth 1.0 m). The local map,
    // searched from the LiDAR's pose with its depth gate, refines it.
    add_as_proposed(OtherStart::Source::lidar, *T_lidar);
  }
  if (last_frame_ && options_.road_start) {
    // The road's own start (TrackerOptions::road_start), searched in the local map as it is, as the
    // LiDAR's: the brute-force matches would pull it back onto the vehicles. After the LiDAR's, which
    // stands on the whole scan against standing still, where the road's stands on a few matches: a
    // start within a step's tolerance of one already judged is not judged again (traffic seed 56,
    // frame 1: the road's 0.67 m, judged first, kept the LiDAR's 0.90 m out, the truth 1.0 m).
    const Stopwatch watch;
    const auto T_road = estimate_road_motion(camera_, *last_frame_, frame, options_);
    logger()->debug("frame {}: the road's keypoints alone start {} ({:.1f} ms)", frame.index,
                    T_road ? fmt::format("{:.2f} m from the last frame", T_road->translation().norm())
                           : std::string("nowhere"),
                    watch.elapsed_ms());
    if (T_road) add_as_proposed(OtherStart::Source::road, *T_road);
  }
  auto optimise = [&](Frame& f) {
    const int inliers = optimise_pose(f);
    discard_outliers(f);
    return inliers >= options_.min_pose_inliers;
  };
  std::erase_if(others, [&](OtherStart& other) { return !other.as_proposed() && !optimise(other.frame); });
  return optimise(frame);
}

bool Tracker::disagrees_with_pose(const Frame& frame, std::size_t i, const Eigen::Vector3d& p_world, double slack) const {
  const Keypoint& kp = frame.keypoints[i];
  const Eigen::Vector3d predicted = frame.T_cam_world * p_world;
  if (predicted.z() <= 0.0) return true;
  if (frame.depth_sigma[i] > 0.0F) {
    const Eigen::Vector3d measured = camera_.unproject(Eigen::Vector2d(kp.x, kp.y), frame.depth[i]);
    return (predicted - measured).norm() > slack + options_.motion_gate_factor * depth_tolerance(measured.z(), options_);
  }
  // no depth (e.g. above the LiDAR's field of view): as far off as guided matching would search
  const double radius = options_.motion_radius * level_scale(map_, kp.level);
  return (camera_.project_unchecked(predicted) - Eigen::Vector2d(kp.x, kp.y)).norm() > radius;
}

void Tracker::drop_moving_matches(Frame& frame, double slack) const {
  if (options_.motion_gate_factor <= 0.0) return;
  std::shared_lock lock(map_.mutex());
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!frame.landmarks[i].valid()) continue;
    const Landmark* l = map_.landmark(frame.landmarks[i]);
    if (l == nullptr || (!frame.is_moving(i) && !disagrees_with_pose(frame, i, l->position, slack))) continue;
    frame.landmarks[i] = LandmarkId{};
  }
}

std::pair<std::vector<KeyframeId>, KeyframeId> Tracker::local_map_around(const Frame& frame,
                                                                         KeyframeId reference) const {
  std::map<KeyframeId, int> votes;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const Landmark* l = frame.landmarks[i].valid() ? map_.landmark(frame.landmarks[i]) : nullptr;
    if (l == nullptr) continue;
    for (const auto& [kf, index] : l->observations) ++votes[kf];
  }
  std::vector<std::pair<int, KeyframeId>> sorted;
  for (const auto& [kf, n] : votes) sorted.emplace_back(n, kf);
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second > b.second; });
  std::vector<KeyframeId> keyframes;
  auto push = [&](KeyframeId id) {
    if (std::find(keyframes.begin(), keyframes.end(), id) != keyframes.end()) return;
    keyframes.push_back(id);
  };
  for (const auto& [n, kf] : sorted) {
    if (static_cast<int>(keyframes.size()) >= options_.max_local_keyframes) break;
    push(kf);
  }
  // Nothing matched yet (the frame was tracked on temporary points only, e.g. after a loss): search
  // around the reference keyframe rather than in an empty local map.
  if (keyframes.empty() && map_.keyframe(reference) != nullptr) push(reference);
  const std::size_t direct = keyframes.size();
  for (std::size_t i = 0; i < direct && static_cast<int>(keyframes.size()) < options_.max_local_keyframes; ++i) {
    for (const KeyframeId n : map_.best_covisible(keyframes[i], 10)) {
      if (static_cast<int>(keyframes.size()) >= options_.max_local_keyframes) break;
      push(n);
    }
  }
  return {std::move(keyframes), sorted.empty() ? reference : sorted.front().second};
}

int Tracker::landmarks_in_view(const Eigen::Isometry3d& T_cam_world, KeyframeId reference) const {
  std::shared_lock lock(map_.mutex());
  const Eigen::Vector3d center = T_cam_world.inverse().translation();
  int count = 0;
  for (const LandmarkId id : map_.landmarks_seen_by(local_map_around(Frame{}, reference).first)) {
    const Landmark* l = map_.landmark(id);
    if (l != nullptr && view_landmark(*l, T_cam_world, center, camera_, map_.options(), options_.min_view_cos)) ++count;
  }
  return count;
}

Tracker::LocalMapResult Tracker::track_local_map(Frame& frame, KeyframeId reference, std::size_t relocalisation_frame,
                                                 ViewLog& views) const {
  LocalMapResult result;
  std::vector<detail::ProjectedLandmark> candidates;
  {
    std::shared_lock lock(map_.mutex());
    auto [keyframes, new_reference] = local_map_around(frame, reference);
    result.reference = new_reference;
    std::vector<LandmarkId> matched;
    for (const LandmarkId l : frame.landmarks) {
      if (l.valid()) matched.push_back(l);
    }
    std::sort(matched.begin(), matched.end());
    const Eigen::Isometry3d T_world_cam = frame.T_cam_world.inverse();
    const Eigen::Vector3d center = T_world_cam.translation();
    const MapOptions& map_options = map_.options();
    for (const LandmarkId id : map_.landmarks_seen_by(keyframes)) {
      if (std::binary_search(matched.begin(), matched.end(), id)) continue;
      const Landmark* l = map_.landmark(id);
      if (l == nullptr) continue;
      const auto view = view_landmark(*l, frame.T_cam_world, center, camera_, map_options, options_.min_view_cos);
      if (!view) continue;
      ++result.visible;
      views.visible.push_back(id);
      detail::ProjectedLandmark c;
      c.id = id;
      c.descriptor = l->descriptor;
      c.x = static_cast<float>(view->pixel.x());
      c.y = static_cast<float>(view->pixel.y());
      c.radius = static_cast<float>(options_.local_map_radius * level_scale(map_, view->level));
      c.min_level = std::max(0, view->level - 1);
      c.max_level = view->level;
      c.depth = static_cast<float>(view->p_cam.z());
      candidates.push_back(c);
    }
    const detail::DepthGate gate{static_cast<float>(options_.depth_gate_sigmas),
                                 static_cast<float>(options_.depth_gate_min_local_map)};
    detail::match_projected(frame, candidates, options_.max_hamming, options_.local_map_ratio, false, nullptr, gate);
  }
  result.inliers = optimise_pose(frame, {}, relocalisation_frame == frame.index);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.landmarks[i].valid() && !frame.outlier[i]) views.found.push_back(frame.landmarks[i]);
  }
  discard_outliers(frame);
  result.ok = support_state(result.inliers, frames_since(frame, relocalisation_frame), options_) == TrackState::Ok;
  return result;
}

bool Tracker::relocalise(Frame& frame) const {
  std::vector<Descriptor> train;
  std::vector<LandmarkId> ids;
  std::vector<Eigen::Vector3d> positions;
  {
    std::shared_lock lock(map_.mutex());
    for (const LandmarkId id : map_.landmark_ids()) {
      const Landmark* l = map_.landmark(id);
      train.push_back(l->descriptor);
      ids.push_back(id);
      positions.push_back(l->position);
    }
  }
  const auto matches =
      detail::match_brute_force(frame.descriptors, train, options_.max_hamming, options_.relocalisation_ratio);
  // A hypothesis needs only a few matches: the map-wide ratio test keeps few of them. It is accepted
  // only when the local-map search from its pose then finds min_ok_inliers_after_relocalisation (as ORB-SLAM).
  if (static_cast<int>(matches.size()) < options_.relocalisation_min_matches) return false;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (const auto& [q, t] : matches) {
    const Eigen::Vector3d& p = positions[static_cast<std::size_t>(t)];
    object.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    image.emplace_back(frame.keypoints[static_cast<std::size_t>(q)].x, frame.keypoints[static_cast<std::size_t>(q)].y);
  }
  cv::Mat K = (cv::Mat_<double>(3, 3) << camera_.fx, 0.0, camera_.cx, 0.0, camera_.fy, camera_.cy, 0.0, 0.0, 1.0);
  cv::Mat rvec, tvec;
  std::vector<int> inlier_indices;
  // Deterministic without touching the caller's cv::theRNG(): OpenCV's RANSAC (non-USAC flags) draws
  // from its own fixed-seed generator (tests/tracking checks both).
  if (!cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false,
                          options_.relocalisation_ransac_iterations,
                          static_cast<float>(options_.relocalisation_ransac_px),
                          options_.relocalisation_ransac_confidence, inlier_indices, cv::SOLVEPNP_EPNP)) {
    return false;
  }
  if (static_cast<int>(inlier_indices.size()) < options_.min_pose_inliers) return false;
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Re(r, c) = R.at<double>(r, c);
  }
  frame.T_cam_world = make_isometry(Re, Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  for (const int i : inlier_indices) {
    const auto& [q, t] = matches[static_cast<std::size_t>(i)];
    frame.landmarks[static_cast<std::size_t>(q)] = ids[static_cast<std::size_t>(t)];
  }
  const int inliers = optimise_pose(frame, {}, true);
  discard_outliers(frame);
  return inliers >= options_.min_pose_inliers;
}

bool Tracker::need_keyframe(const Frame& frame, int inliers, bool mapping_idle) const {
  std::shared_lock lock(map_.mutex());
  const int keyframes = static_cast<int>(map_.keyframe_count());
  if (last_relocalisation_frame_ > 0 &&
      frame.index < last_relocalisation_frame_ + static_cast<std::size_t>(options_.max_frames_between_keyframes) &&
      keyframes > options_.max_frames_between_keyframes) {
    return false;
  }
  KeyframeEvidence e;
  e.keyframes = keyframes;
  e.frames_since_keyframe = static_cast<int>(frame.index - last_keyframe_frame_);
  e.mapping_idle = mapping_idle;
  e.inliers = inliers;
  // established: seen by 3 keyframes (2 while the map has two or fewer); the frame's inliers are
  // counted the same way as the reference's landmarks (TrackerOptions::reference_ratio_threshold)
  const int min_observations = keyframes <= 2 ? 2 : 3;
  const Keyframe* ref = map_.keyframe(reference_);
  e.reference_established = ref != nullptr ? ref->tracked_landmarks(min_observations, map_) : 0;
  if (ref != nullptr && options_.reference_landmark_ratio > 0.0) e.reference_landmarks = ref->tracked_landmarks(1, map_);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const bool tracked = frame.landmarks[i].valid() && !frame.outlier[i];
    if (tracked) {
      const Landmark* l = map_.landmark(frame.landmarks[i]);
      if (l != nullptr && std::cmp_greater_equal(l->observations.size(), min_observations)) ++e.established_inliers;
    }
    if (frame.depth_sigma[i] <= 0.0F || frame.depth[i] >= options_.close_depth) continue;
    if (tracked) ++e.tracked_close;
    else ++e.untracked_close;
  }
  return keyframe_due(e, options_);
}

KeyframeId Tracker::make_keyframe(const Frame& frame) {
  std::unique_lock lock(map_.mutex());
  Keyframe made = keyframe_from(frame, options_);
  if (const Keyframe* previous = map_.keyframe(reference_)) {
    made.previous = reference_;
    made.T_cam_previous = frame.T_cam_world * previous->T_cam_world.inverse();
  }
  const KeyframeId id = map_.add_keyframe(std::move(made));
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.landmarks[i].valid() && !frame.outlier[i]) map_.add_observation(frame.landmarks[i], id, static_cast<int>(i));
  }
  reference_ = id;
  last_keyframe_frame_ = frame.index;
  return id;
}

std::optional<Eigen::Isometry3d> Tracker::follow_map_correction(const Eigen::Isometry3d& T_ref_world_before) {
  std::optional<Eigen::Isometry3d> T_ref_world_after;
  {
    std::shared_lock lock(map_.mutex());
    T_ref_world_after = map_.keyframe_pose(reference_);
  }
  if (!T_ref_world_after) return std::nullopt;
  // A frame rigidly attached to the reference: T_cam_world' = T_cam_ref * T_ref_world'.
  const Eigen::Isometry3d T_before_after = T_ref_world_before.inverse() * *T_ref_world_after;
  if (last_frame_) last_frame_->T_cam_world = last_frame_->T_cam_world * T_before_after;
  if (last_tracked_frame_) last_tracked_frame_->T_cam_world = last_tracked_frame_->T_cam_world * T_before_after;
  return T_before_after;
}

}  // namespace rgbl
