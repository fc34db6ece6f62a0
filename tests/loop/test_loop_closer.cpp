#include "rgbl/loop/loop_closer.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "mapped_drive.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <numbers>
#include <utility>

namespace {

// A fresh map holding the live keyframes and landmarks of `source` (ids renumbered, order kept), so a
// test can change it.
void copy_map(const rgbl::Map& source, rgbl::Map& target) {
  std::map<int, rgbl::KeyframeId> keyframe_of;
  std::map<int, rgbl::LandmarkId> landmark_of;
  for (const rgbl::KeyframeId id : source.keyframe_ids()) {
    rgbl::Keyframe k = *source.keyframe(id);
    k.landmarks.assign(k.keypoints.size(), rgbl::LandmarkId{});
    keyframe_of[id.value] = target.add_keyframe(std::move(k));
  }
  for (const rgbl::LandmarkId id : source.landmark_ids()) {
    const rgbl::Landmark& l = *source.landmark(id);
    const auto reference = keyframe_of.find(l.reference_keyframe.value);
    if (reference == keyframe_of.end()) continue;
    const rgbl::LandmarkId copy = target.add_landmark(l.position, reference->second);
    landmark_of[id.value] = copy;
    for (const auto& [keyframe, keypoint] : l.observations) {
      const auto k = keyframe_of.find(keyframe.value);
      if (k == keyframe_of.end()) continue;
      target.keyframe(k->second)->landmarks[static_cast<std::size_t>(keypoint)] = copy;
      target.add_observation(copy, k->second, keypoint);
    }
    target.update_landmark(copy);
  }
  for (const auto& [old_id, id] : keyframe_of) {
    // the spanning tree as the source has it (update_covisibility alone would pick parents by weight)
    const rgbl::KeyframeId parent = source.keyframe(rgbl::KeyframeId{old_id})->parent;
    target.keyframe(id)->parent = parent.valid() ? keyframe_of.at(parent.value) : rgbl::KeyframeId{};
    target.update_covisibility(id);
  }
}

}  // namespace

TEST_CASE("loop closer: a revisit of real keyframes with drift is closed and corrected") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  const auto sequence = rgbl::open_kitti_odometry(*dir);
  rgbl::SystemOptions no_loops;
  no_loops.loop_closing.enabled = false;
  const rgbl::test::Mapped m = rgbl::test::map_drive(sequence, 30, no_loops);
  // the car ahead in frame 0 leaves nothing a revisit could be aligned to
  const int unfound = rgbl::test::unfound_first_keyframe_landmarks(m.system->map(), no_loops.mapping.min_found_ratio);
  CAPTURE(unfound);  // measured: 9 after 30 frames (341 before)
  CHECK(unfound <= 30);
  rgbl::Map map;
  copy_map(m.system->map(), map);
  const auto originals = map.keyframe_ids();
  REQUIRE(originals.size() >= 6);

  rgbl::LoopClosingOptions options;
  options.min_keyframe_gap = 3;  // 30 frames give few keyframes
  options.global_ba = true;       // off by default (docs/loop-closing.md); what it does is checked here
  rgbl::LoopCloser closer(m.calibration.camera, options);
  const auto scan_of = [&](const rgbl::Keyframe& k) { return sequence->load(k.frame_index).scan; };
  for (const rgbl::KeyframeId id : originals) {
    const auto scan = scan_of(*map.keyframe(id));
    const rgbl::LoopCloserStep step = closer.process(map, id, scan);
    CHECK_FALSE(step.closure.has_value());  // one pass down a road: nothing to close
  }

  // The drive comes back: keyframes 0, 1, 2 seen again (same images and scans), but odometry has
  // drifted by 1.5 m sideways, 0.5 m up and 2 degrees of heading. Chained after the last keyframe in
  // the spanning tree, with no landmarks of their own (the worst case: nothing ties them to the map).
  const Eigen::Isometry3d drift = rgbl::se3_exp((rgbl::Vector6d() << 1.5, -0.5, 0.0, 0.0, 2.0 * std::numbers::pi / 180.0, 0.0).finished());
  std::vector<rgbl::KeyframeId> revisits;
  for (std::size_t k = 0; k < 3; ++k) {
    rgbl::Keyframe copy = *map.keyframe(originals[k]);
    copy.landmarks.assign(copy.keypoints.size(), rgbl::LandmarkId{});
    copy.T_cam_world = copy.T_cam_world * drift;
    const rgbl::KeyframeId id = map.add_keyframe(std::move(copy));
    map.keyframe(id)->parent = revisits.empty() ? originals.back() : revisits.back();
    revisits.push_back(id);
  }
  const auto error_m = [&](std::size_t k) {
    return (map.keyframe(revisits[k])->center() - map.keyframe(originals[k])->center()).norm();
  };
  const double before = error_m(2);
  std::optional<rgbl::LoopClosure> closure;
  int closures = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    const rgbl::LoopCloserStep step = closer.process(map, revisits[k], scan_of(*map.keyframe(revisits[k])));
    CAPTURE(k, step.candidates, step.verified, step.consistent);
    CHECK(step.verified >= 1);  // each revisit is recognised and verified
    if (step.closure) {
      ++closures;
      closure = step.closure;
    }
  }
  // closed once, on the first revisit: the keyframes before it are 30 frames down the road and do not
  // see the place, so the original's covisible keyframes confirm it (the next two revisits then
  // agree with the corrected map and only confirm it; since keypoints map pixel centre to pixel
  // centre across pyramid levels, revisit 1 verifies 2 places but its loop does not pass the
  // consistency check, so it confirms nothing, 2026-11-28: a loop left unconfirmed, never a wrong
  // correction)
  REQUIRE(closures == 1);
  CHECK(closure->current == revisits[0]);
  CHECK(closure->matched == originals[0]);
  CHECK(closure->correction_m > 1.0);
  CHECK(closer.loops().size() == 3);
  CHECK(closer.stats().confirming >= 1);
  // the revisits had no landmarks: fusion gives them the originals' (measured: 192 fused), and the
  // global bundle adjustment takes every keyframe of the map
  CHECK(closure->fused_landmarks >= 50);
  CHECK(map.keyframe(revisits[0])->covisibility.contains(originals[0]));
  CHECK(std::cmp_equal(closure->global_ba_keyframes, map.keyframe_count()));
  CHECK(closure->global_ba_landmarks > 0);
  const double after = error_m(2);
  CAPTURE(before, after, error_m(0), error_m(1), closure->correction.loop_error_before_m,
          closure->correction.loop_error_after_m);
  CHECK(before > 1.5);
  CHECK(after < 0.1 * before);
  for (std::size_t k = 0; k < 3; ++k) CHECK(error_m(k) < 0.2);
}

TEST_CASE("loop closer: a real drive without a loop closes nothing and tracks bit-identically") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  rgbl::SystemOptions no_loops;
  no_loops.loop_closing.enabled = false;
  const rgbl::test::Mapped with = rgbl::test::map_drive(rgbl::open_kitti_odometry(*dir), 30);
  const rgbl::test::Mapped without = rgbl::test::map_drive(rgbl::open_kitti_odometry(*dir), 30, no_loops);
  REQUIRE(with.results.size() == 30);
  for (const auto& r : with.results) CHECK_FALSE(r.loop_closure.has_value());
  const auto a = with.system->trajectory();
  const auto b = without.system->trajectory();
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i].T_world_cam.matrix() == b[i].T_world_cam.matrix());
}

TEST_CASE("loop closing options are checked, naming the field") {
  CHECK_NOTHROW(rgbl::LoopClosingOptions{}.validate());
  // each change to the defaults must be refused with the field's key in the message
  const auto refused = [](void (*change)(rgbl::LoopClosingOptions&), const char* key) {
    rgbl::LoopClosingOptions o;
    change(o);
    CHECK_THROWS_WITH(o.validate(), Catch::Contains(key));
  };
  refused([](auto& o) { o.places.scan_context.max_distance = 0.0; }, "loop_closing.places.scan_context.max_distance");
  refused([](auto& o) { o.places.methods = {"netvlad"}; }, "loop_closing.places");
  refused([](auto& o) { o.places.methods = {"bow", "bow"}; }, "loop_closing.places");
  refused([](auto& o) { o.places.bow.min_score = 1.0; }, "loop_closing.places.bow.min_score");
  refused([](auto& o) { o.consistent_keyframes = 0; }, "loop_closing.consistent_keyframes");
  refused([](auto& o) { o.verification.guided_radius_px = 0.0; }, "loop_verification.guided_radius_px");
  refused([](auto& o) { o.places.scan_context.descriptor.sectors = 1; }, "scan_context.sectors");
  refused([](auto& o) { o.fusion_neighbours = -1; }, "loop_closing.fusion_neighbours");
  refused([](auto& o) { o.fusion.radius_px = 0.0; }, "fusion.radius_px");
  refused([](auto& o) { o.global_ba_options.iterations = 0; }, "bundle_adjustment.iterations");
  refused([](auto& o) { o.global_ba_pairs.road_max_distance = -1.0; }, "keyframe_pairs.road_max_distance");
  refused([](auto& o) { o.max_drift_percent = 0.0; }, "loop_closing.max_drift_percent");
  refused([](auto& o) { o.max_drift_deg_per_100m = -1.0; }, "loop_closing.max_drift_deg_per_100m");
  refused([](auto& o) { o.drift_allowance_m = -0.1; }, "loop_closing.drift_allowance_m");
  refused([](auto& o) { o.drift_allowance_deg = -0.1; }, "loop_closing.drift_allowance_deg");
  rgbl::SystemOptions s;
  s.loop_closing.min_correction_m = -1.0;
  CHECK_THROWS_WITH(s.validate(), Catch::Contains("loop_closing.min_correction_m"));
}
