// The state rule (rgbl/tracking/support.hpp): ok needs ORB-SLAM's 30 inliers, 50 within a second of a
// relocalisation; a step is plausible within the pose noise, the velocity's error and 1 g.
#include "rgbl/tracking/support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace {

Eigen::Isometry3d camera_at(double x, double z, double yaw_deg = 0.0) {
  // T_world_cam: at (x, 0, z), turned by yaw about the camera's y axis; returned as T_cam_world
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.linear() = Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_world_cam.translation() = Eigen::Vector3d(x, 0.0, z);
  return T_world_cam.inverse();
}

}  // namespace

TEST_CASE("support: ok needs 30 inliers, 50 within the relocalisation window", "[tracking][support]") {
  const rgbl::TrackerOptions options;
  using rgbl::TrackState;
  CHECK(rgbl::support_state(30, std::nullopt, options) == TrackState::Ok);
  CHECK(rgbl::support_state(29, std::nullopt, options) == TrackState::Weak);
  CHECK(rgbl::support_state(4, std::nullopt, options) == TrackState::Weak);  // the real drive's frame 118+
  CHECK(rgbl::support_state(0, std::nullopt, options) == TrackState::Weak);
  // the relocalised frame itself and the next 9 need 50
  CHECK(rgbl::support_state(49, 0, options) == TrackState::Weak);
  CHECK(rgbl::support_state(50, 0, options) == TrackState::Ok);
  CHECK(rgbl::support_state(49, 9, options) == TrackState::Weak);
  CHECK(rgbl::support_state(30, 10, options) == TrackState::Ok);
  CHECK(rgbl::support_state(29, 10, options) == TrackState::Weak);

  CHECK(std::string(rgbl::to_string(TrackState::Weak)) == "weak");
  CHECK(rgbl::has_pose(TrackState::Weak));
  CHECK(rgbl::has_pose(TrackState::Ok));
  CHECK_FALSE(rgbl::has_pose(TrackState::Lost));
  CHECK_FALSE(rgbl::has_pose(TrackState::NotInitialised));
}

TEST_CASE("support: a step is plausible within pose noise, velocity error and 1 g", "[tracking][support]") {
  const rgbl::TrackerOptions options;  // 0.25 m + 0.1 * step + 10 m/s^2 * dt^2 / 2, 3 deg
  const Eigen::Isometry3d predicted = camera_at(0.0, 1.3);  // a 1.3 m step predicted, 0.1 s
  const double allowed = 0.25 + 0.1 * 1.3 + 0.5 * 10.0 * 0.01;
  const auto at = [&](double x, double z, double yaw = 0.0) {
    return rgbl::check_step(camera_at(x, z, yaw), predicted, 1.3, 0.1, options);
  };
  CHECK(at(0.0, 1.3).plausible);
  CHECK(at(0.0, 1.3).translation_m == Approx(0.0).margin(1e-12));
  CHECK(at(0.0, 1.3).allowed_translation_m == Approx(allowed));
  CHECK(at(0.0, 1.3 + allowed - 0.01).plausible);
  CHECK_FALSE(at(0.0, 1.3 + allowed + 0.01).plausible);
  CHECK(at(0.0, 1.3 + allowed + 0.01).translation_m == Approx(allowed + 0.01));
  CHECK_FALSE(at(allowed + 0.01, 1.3).plausible);        // sideways counts the same
  CHECK_FALSE(at(0.0, 3.7 * 1.3).plausible);              // the real drive's 3.7x steps
  CHECK_FALSE(at(0.0, 1.3 + 8.4).plausible);              // and its 8.4 m jump
  CHECK(at(0.0, 1.3, 2.9).plausible);
  CHECK_FALSE(at(0.0, 1.3, 3.1).plausible);
  CHECK(at(0.0, 1.3, 3.1).rotation_deg == Approx(3.1));
  // a turn harder than predicted leaves the centre within reach; a step too long does not
  CHECK(at(0.0, 1.3, 3.1).translation_plausible);
  CHECK_FALSE(at(0.0, 1.3 + allowed + 0.01).translation_plausible);
  CHECK_FALSE(at(0.0, 1.3 + allowed + 0.01, 3.1).translation_plausible);
  // a frame that comes late (dropped frames) may deviate more: the acceleration term grows with dt^2
  const auto late = rgbl::check_step(camera_at(0.0, 1.3 + 0.6), predicted, 1.3, 0.3, options);
  CHECK(late.allowed_translation_m == Approx(0.25 + 0.13 + 0.45));
  CHECK(late.plausible);
  // an unknown time difference adds nothing
  CHECK(rgbl::check_step(predicted, predicted, 1.3, 0.0, options).allowed_translation_m == Approx(0.38));
}

TEST_CASE("support: after a gap a car that was moving cannot have stayed put: it brakes, it does not reverse",
          "[tracking][support]") {
  const rgbl::TrackerOptions options;  // 1 g
  const Eigen::Vector3d last(0.0, 0.0, 0.0);
  // 11.2 m/s, 2.1 s since the last frame (suburban seed 2, frames 15-34 left out): 23.52 m predicted.
  // Braking at 1 g it stops after 1.12 s and 6.27 m, so it falls short by at most 17.25 m (+ 0.25 m +
  // 10 % of the step); the isotropic bound alone allows 0.25 + 2.35 + 22.05 m either way.
  const double s = 11.2 * 2.1, reach = 10.0 * 2.1 * 2.1;
  const Eigen::Isometry3d predicted = camera_at(0.0, s);
  const double allowed_short = 0.25 + 0.1 * s + (s - s * s / (2.0 * reach));
  CHECK(allowed_short == Approx(0.25 + 2.352 + 17.248).margin(1e-3));
  const auto at = [&](double x, double z) { return rgbl::check_step(camera_at(x, z), predicted, last, 2.1, options); };
  // where it was before the gap: 23.5 m short, within the isotropic 24.65 m, but not within braking
  const auto stayed = at(0.0, 0.0);
  CHECK(stayed.translation_m == Approx(s));
  CHECK(stayed.translation_m < stayed.allowed_translation_m);
  CHECK(stayed.shortfall_m == Approx(s));
  CHECK(stayed.allowed_shortfall_m == Approx(allowed_short));
  CHECK_FALSE(stayed.translation_plausible);
  CHECK_FALSE(stayed.plausible);
  // braking hard and stopping early is within reach; so is going on, or further, as before
  CHECK(at(0.0, s - allowed_short + 0.05).plausible);
  CHECK_FALSE(at(0.0, s - allowed_short - 0.05).plausible);
  CHECK(at(0.0, s + 20.0).plausible);
  CHECK(at(0.0, s + 20.0).shortfall_m == Approx(-20.0));
  // sideways is not short: the isotropic bound judges it
  CHECK(at(10.0, s).plausible);
  CHECK(at(10.0, s).shortfall_m == Approx(0.0).margin(1e-9));
  // at 10 Hz a car at speed cannot stop within the frame: exactly the isotropic bound, as without the
  // last centre
  const Eigen::Isometry3d next = camera_at(0.0, 1.3);
  for (const double z : {0.0, 0.5, 0.7, 1.3, 2.0}) {
    const auto with_last = rgbl::check_step(camera_at(0.0, z), next, last, 0.1, options);
    const auto without = rgbl::check_step(camera_at(0.0, z), next, 1.3, 0.1, options);
    CAPTURE(z);
    CHECK(with_last.plausible == without.plausible);
    CHECK(with_last.allowed_translation_m == Approx(without.allowed_translation_m));
  }
}

TEST_CASE("support: a run of steps each within reach can still slide the speed beyond a vehicle's reach",
          "[tracking][support]") {
  const rgbl::TrackerOptions options;  // 0.3 s window, 1 g
  // 10 Hz at 9.5 m/s (0.95 m a frame) along z, then the steps of traffic seed 24 at nFeatures 1900
  // on frames 9-10 (0.76, 0.41 m): each within check_step's 0.25 + 10 % + 0.05 m of the one before
  std::vector<rgbl::PlacedCentre> recent;
  for (int i = 0; i <= 8; ++i) recent.push_back({0.1 * i, Eigen::Vector3d(0.0, 0.0, 0.95 * i)});
  const double z8 = 0.95 * 8;
  recent.push_back({0.9, Eigen::Vector3d(0.0, 0.0, z8 + 0.76)});
  // frame 10: anchor frame 7 (0.3 s back), the speed over frames 4-7 carries it to z7 + 2.85
  const auto at10 = rgbl::check_speed(recent, 1.0, Eigen::Vector3d(0.0, 0.0, z8 + 0.76 + 0.41), options);
  REQUIRE(at10);
  CHECK(at10->frames_back == 3);
  CHECK(at10->span_s == Approx(0.3));
  CHECK(at10->velocity.z() == Approx(9.5));
  CHECK(at10->expected_centre.z() == Approx(0.95 * 7 + 2.85));
  const double allowed = 0.25 + 0.1 * 2.85 + 0.5 * 10.0 * 0.09;  // allowed_step(2.85 m, 0.3 s)
  CHECK(at10->allowed_m == Approx(allowed));
  CHECK(at10->deviation_m == Approx(0.95 * 7 + 2.85 - (z8 + 1.17)));  // 0.73 m: within the 0.99 m
  CHECK(at10->plausible);
  recent.push_back({1.0, Eigen::Vector3d(0.0, 0.0, z8 + 1.17)});
  // frame 11 at 0.20 m more: 1.51 m short of the anchor's 2.85 m, beyond what braking at 1 g explains
  const auto at11 = rgbl::check_speed(recent, 1.1, Eigen::Vector3d(0.0, 0.0, z8 + 1.37), options);
  REQUIRE(at11);
  CHECK(at11->deviation_m == Approx(z8 + 2.85 - (z8 + 1.37)));
  CHECK_FALSE(at11->plausible);
  // sideways by as much is as far out of reach, and the true 1.0 m step after the slide is within it
  CHECK_FALSE(rgbl::check_speed(recent, 1.1, Eigen::Vector3d(1.48, 0.0, z8 + 2.85), options)->plausible);
  CHECK(rgbl::check_speed(recent, 1.1, Eigen::Vector3d(0.0, 0.0, z8 + 2.17), options)->plausible);
  // braking at 3.5 m/s^2 (the traffic scenario's stop) is well within reach
  std::vector<rgbl::PlacedCentre> braking;
  double z = 0.0, v = 9.5;
  for (int i = 0; i <= 12; ++i) {
    braking.push_back({0.1 * i, Eigen::Vector3d(0.0, 0.0, z)});
    z += v * 0.1;
    v -= 0.35;
  }
  const auto brake = rgbl::check_speed(braking, 1.3, Eigen::Vector3d(0.0, 0.0, z), options);
  REQUIRE(brake);
  CHECK(brake->deviation_m == Approx(0.315));  // 3 x 0.67 m against 0.60 + 0.565 + 0.53 m
  CHECK(brake->plausible);
  // nothing to say: too short a history, frames as far apart as the window (the step check's case), off
  CHECK_FALSE(rgbl::check_speed(std::span(recent).first(2), 0.2, Eigen::Vector3d::Zero(), options));
  std::vector<rgbl::PlacedCentre> slow;
  for (int i = 0; i <= 5; ++i) slow.push_back({0.3 * i, Eigen::Vector3d(0.0, 0.0, 2.85 * i)});
  CHECK_FALSE(rgbl::check_speed(slow, 1.8, Eigen::Vector3d(0.0, 0.0, 0.0), options));
  rgbl::TrackerOptions off;
  off.speed_window_s = 0.0;
  CHECK_FALSE(rgbl::check_speed(recent, 1.1, Eigen::Vector3d::Zero(), off));
}

TEST_CASE("support: the thresholds are validated", "[tracking][support]") {
  rgbl::TrackerOptions options;
  options.min_ok_inliers = 5;  // below min_pose_inliers (10)
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("tracker.min_ok_inliers"));
  options = {};
  options.min_ok_inliers_after_relocalisation = 20;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("tracker.min_ok_inliers_after_relocalisation"));
  options = {};
  options.step_tolerance_rotation_deg = -1.0;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("tracker.step_tolerance_rotation_deg"));
  options = {};
  options.start_doubt_s = -0.5;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("tracker.start_doubt_s"));
  options = rgbl::TrackerOptions{};
  options.speed_window_s = -0.1;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("tracker.speed_window_s"));
  options = {};
  options.max_acceleration = -1.0;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("tracker.max_acceleration"));
  CHECK_NOTHROW(rgbl::TrackerOptions{}.validate());
}

TEST_CASE("keyframe rule: like with like, established inliers against the reference's established landmarks",
          "[tracking][support]") {
  const rgbl::TrackerOptions options;  // 0.3 of the reference's established, 0.25 urgent, 10 frames
  // 10 frames after the last keyframe, mapping busy, no need for close points; 500 inliers, most of
  // them on young landmarks from the last keyframe's depth, 46 of the reference's 150 established
  rgbl::KeyframeEvidence e{.keyframes = 20, .frames_since_keyframe = 10, .mapping_idle = false,
                           .reference_established = 150, .inliers = 500, .established_inliers = 46,
                           .tracked_close = 300, .untracked_close = 10};
  CHECK_FALSE(rgbl::keyframe_due(e, options));  // > 30 % still tracked, however many young ones
  e.established_inliers = 44;                    // < 45
  CHECK(rgbl::keyframe_due(e, options));
  e.inliers = 100;  // ORB-SLAM's count (every inlier against 75 %) would have waited for < 112
  CHECK(rgbl::keyframe_due(e, options));
  // before max_frames_between_keyframes, with mapping busy: only when urgent (< 25 %, 37.5)
  e.frames_since_keyframe = 3;
  CHECK_FALSE(rgbl::keyframe_due(e, options));
  e.mapping_idle = true;
  CHECK(rgbl::keyframe_due(e, options));
  e.mapping_idle = false;
  e.established_inliers = 37;
  CHECK(rgbl::keyframe_due(e, options));
  e.inliers = 15;  // never on min_keyframe_inliers (15) inliers or fewer
  CHECK_FALSE(rgbl::keyframe_due(e, options));

  // 0.25 by default (docs/accuracy.md, "Keyframes when all the reference's landmarks thin out"): where
  // keyframes are sparse and few landmarks established, due once the frame tracks fewer than a quarter
  // of all the reference's landmarks, however many of the few established it keeps
  rgbl::KeyframeEvidence sparse{.keyframes = 2, .frames_since_keyframe = 20, .mapping_idle = false,
                                .reference_established = 126, .reference_landmarks = 760, .inliers = 191,
                                .established_inliers = 120, .tracked_close = 191, .untracked_close = 0};
  REQUIRE(options.reference_landmark_ratio == 0.25);
  CHECK_FALSE(rgbl::keyframe_due(sparse, options));  // 191 of 760: more than 25 %
  sparse.inliers = 189;                              // < 190
  CHECK(rgbl::keyframe_due(sparse, options));
  rgbl::TrackerOptions off = options;
  off.reference_landmark_ratio = 0.0;
  CHECK_FALSE(rgbl::keyframe_due(sparse, off));  // off: the established rule alone waits

  // close points needed (< 100 tracked and > 70 untracked within close_depth): due at once
  rgbl::KeyframeEvidence close{.keyframes = 20, .frames_since_keyframe = 1, .mapping_idle = false,
                               .reference_established = 150, .inliers = 400, .established_inliers = 140,
                               .tracked_close = 99, .untracked_close = 71};
  CHECK(rgbl::keyframe_due(close, options));
  close.untracked_close = 70;
  CHECK_FALSE(rgbl::keyframe_due(close, options));

  // while the map has one keyframe: 40 % (initial_reference_ratio_threshold)
  rgbl::KeyframeEvidence second{.keyframes = 1, .frames_since_keyframe = 10, .mapping_idle = false,
                                .reference_established = 100, .inliers = 300, .established_inliers = 40,
                                .tracked_close = 300, .untracked_close = 0};
  CHECK_FALSE(rgbl::keyframe_due(second, options));
  second.established_inliers = 39;
  CHECK(rgbl::keyframe_due(second, options));
}

TEST_CASE("support: the motion model is suspect when the map or the recent frames disagree with it",
          "[tracking][support]") {
  const rgbl::TrackerOptions options;  // 5 % of the local map, 20 % of the last frame's inliers
  REQUIRE(options.min_pose_inliers == 10);
  rgbl::MotionEvidence e;
  e.motion_inliers = 150;
  e.last_inliers = 160;
  e.keypoints = e.last_keypoints = 1950;
  e.local_inliers = 200;
  e.local_visible = 1000;
  CHECK_FALSE(rgbl::motion_suspect(e, options));
  SECTION("a jump onto a repetitive road: both checks fire") {
    // sequence 04, frame 35 fed after 14: the motion model keeps 22 of 160, the local map 31 of 1000
    e.motion_inliers = 22;
    CHECK(rgbl::motion_suspect(e, options));  // 22 < 32
    e.motion_inliers = 32;
    CHECK_FALSE(rgbl::motion_suspect(e, options));
    e.local_inliers = 31;
    CHECK(rgbl::motion_suspect(e, options));  // 31 < 50
    e.local_inliers = 50;
    CHECK_FALSE(rgbl::motion_suspect(e, options));
  }
  SECTION("a frame on plain surfaces offers fewer keypoints: the yardstick shrinks with them") {
    e.last_inliers = 552;
    e.motion_inliers = 101;
    CHECK(rgbl::motion_suspect(e, options));  // 101 < 110.4 with as many keypoints as the last frame
    e.keypoints = 1100;                       // 110.4 * 1100 / 1950 = 62.3
    CHECK_FALSE(rgbl::motion_suspect(e, options));
    e.motion_inliers = 62;
    CHECK(rgbl::motion_suspect(e, options));
    // more keypoints than the last frame never raise the bar
    e.keypoints = 3900;
    e.motion_inliers = 111;
    CHECK_FALSE(rgbl::motion_suspect(e, options));
  }
  SECTION("each check judges only where passing means min_pose_inliers points") {
    e.last_inliers = 45;  // 20 % is 9 < 10: mapping lagging behind, no judgement
    e.motion_inliers = 0;
    CHECK_FALSE(rgbl::motion_suspect(e, options));
    e.last_inliers = 0;  // the last frame was not tracked
    CHECK_FALSE(rgbl::motion_suspect(e, options));
    e.local_visible = 150;  // 5 % is 7.5 < 10
    e.local_inliers = 0;
    CHECK_FALSE(rgbl::motion_suspect(e, options));
    e.last_keypoints = 0;  // no last frame: the share is taken as 1
    e.last_inliers = 160;
    CHECK(rgbl::motion_suspect(e, options));
  }
}

TEST_CASE("support: the direction of travel is learned in the camera's frame, on an arc and backing up",
          "[tracking][support]") {
  // A camera mounted 1.5 deg to the left of the car's axis and pitched 0.8 deg down drives a 30 m
  // radius arc at 1 m a frame; the car's axis stays on the arc's tangent (the rear axle's path), so
  // in the camera's frame the car moves along a fixed direction.
  const double yaw = 1.5 * std::numbers::pi / 180.0, pitch = 0.8 * std::numbers::pi / 180.0;
  const Eigen::Matrix3d R_car_cam = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const Eigen::Vector3d expected = R_car_cam.transpose() * Eigen::Vector3d::UnitZ();
  const auto camera_on_arc = [&](double s) {  // s metres along the arc (x right, z forward in the world)
    const double radius = 30.0, heading = s / radius;
    Eigen::Isometry3d T_world_car = Eigen::Isometry3d::Identity();
    T_world_car.linear() = Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_world_car.translation() = Eigen::Vector3d(-radius * (1.0 - std::cos(heading)), 0.0, radius * std::sin(heading));
    Eigen::Isometry3d T_world_cam = T_world_car;
    T_world_cam.linear() = T_world_car.linear() * R_car_cam;
    return T_world_cam.inverse();
  };
  rgbl::TrackerOptions options;  // learned after 3 m of steps of at least 0.2 m
  rgbl::TravelDirection travel;
  const auto angle_deg = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  };
  for (int i = 1; i <= 2; ++i) travel.add(camera_on_arc(i - 1.0), camera_on_arc(i), options);
  CHECK_FALSE(travel.direction(options).has_value());  // 2 m seen
  travel.add(camera_on_arc(2.0), camera_on_arc(2.1), options);  // too short to give a direction: not counted
  CHECK_FALSE(travel.direction(options).has_value());
  travel.add(camera_on_arc(2.0), camera_on_arc(3.0), options);
  travel.add(camera_on_arc(3.0), camera_on_arc(4.0), options);  // the chords are a little under 1 m
  REQUIRE(travel.direction(options).has_value());
  CHECK(angle_deg(*travel.direction(options), expected) < 1e-6);
  // the arc's chord is read half-way through the turn, so the direction does not move on the arc...
  for (int i = 4; i < 40; ++i) travel.add(camera_on_arc(i), camera_on_arc(i + 1.0), options);
  CHECK(angle_deg(*travel.direction(options), expected) < 1e-6);
  // ...nor when the car backs up along it (half-metre steps)
  for (int i = 40; i > 30; --i) travel.add(camera_on_arc(i), camera_on_arc(i - 0.5), options);
  CHECK(angle_deg(*travel.direction(options), expected) < 1e-6);
  // a step 10 deg off moves the mean by its share of every step seen: 1 m of about 44 m, 0.22 deg
  const Eigen::Isometry3d T_last = camera_on_arc(30.0);
  Eigen::Isometry3d T_off = T_last;
  const Eigen::Vector3d off_cam = Eigen::AngleAxisd(10.0 * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY()) * expected;
  T_off.translation() = T_last.translation() - off_cam;  // the centre 1 m along off_cam, no turn
  travel.add(T_last, T_off, options);
  CHECK(angle_deg(*travel.direction(options), expected) > 0.2);
  CHECK(angle_deg(*travel.direction(options), expected) < 0.25);
}
