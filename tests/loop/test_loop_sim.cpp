// Loop closing on the simulator, where the truth says which places are the same: on the loop driven
// twice every closure must pair frames of one place and closing must pay off on the whole trajectory;
// on a street of identical blocks, built to fool it, no loop may be closed.

#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/sim/scenarios.hpp"
#include "rgbl/sim/synthetic.hpp"
#include "mapped_drive.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <vector>

namespace {

struct Lap {
  std::vector<rgbl::FrameInput> frames;  // camera 0's image and the scan
  std::vector<Eigen::Isometry3d> truth;
  rgbl::CameraCalibration calibration;
};

Lap generate(rgbl::SyntheticOptions options) {
  options.cameras = {true, false, false, false};
  const rgbl::SyntheticGenerator generator(options);
  Lap l;
  l.calibration = generator.calibration().camera(0);
  for (int i = 0; i < options.frames; ++i) {
    rgbl::FrameInput f;
    f.index = static_cast<std::size_t>(i);
    f.timestamp = generator.timestamp(i);
    f.images[0] = generator.render_image(i, 0);
    f.scan = generator.render_scan(i);
    l.frames.push_back(std::move(f));
    l.truth.push_back(generator.pose(i));
  }
  return l;
}

// Two laps of a 100 m loop (`rgbl demo --path loop --frames 201 --laps 2`): the second lap drives
// exactly the first lap's track, so frame i + 100 is at frame i's place.
const Lap& two_laps() {
  static const Lap lap = [] {
    rgbl::SyntheticOptions options;
    options.frames = 201;
    options.path.kind = rgbl::PathKind::loop;
    options.path.loop_laps = 2;
    return generate(options);
  }();
  return lap;
}

struct Run {
  std::vector<rgbl::TrackResult> results;
  rgbl::LoopClosingStats loops;
  double ate = 0.0;
};

Run track(const Lap& lap, const rgbl::LoopClosingOptions& loop_closing) {
  rgbl::SystemOptions options;
  options.loop_closing = loop_closing;
  const rgbl::test::Mapped m = rgbl::test::track_frames(
      lap.calibration, lap.frames.size(), [&](std::size_t i) -> const rgbl::FrameInput& { return lap.frames[i]; },
      options);
  std::vector<Eigen::Isometry3d> estimate;
  for (const auto& p : m.system->trajectory()) estimate.push_back(p.T_world_cam);
  REQUIRE(estimate.size() == lap.truth.size());
  return {m.results, m.system->loop_statistics(), rgbl::absolute_trajectory_error(estimate, lap.truth).translation.rmse};
}

Run track(const Lap& lap, bool loop_closing) {
  rgbl::LoopClosingOptions options;
  options.enabled = loop_closing;
  return track(lap, options);
}

}  // namespace

TEST_CASE("loop closer: two laps of the simulator's loop are closed where the places are the same") {
  const Lap& lap = two_laps();
  const Run with = track(lap, true);
  const Run without = track(lap, false);
  int closures = 0;
  for (const auto& r : with.results) {
    CHECK(r.state == rgbl::TrackState::Ok);
    if (!r.loop_closure) continue;
    ++closures;
    // a true closure: the two frames are within a few metres of each other in the truth
    const auto& c = *r.loop_closure;
    const double apart = (lap.truth[c.frame_index].translation() - lap.truth[c.matched_frame_index].translation()).norm();
    CAPTURE(c.frame_index, c.matched_frame_index, apart, c.correction_m, c.correction_deg);
    CHECK(apart < 10.0);
    CHECK(c.frame_index >= 100);  // nothing before the first lap is done
  }
  fmt::print("two laps of a 100 m loop: {} closures, ATE {:.3f} m (without loop closing {:.3f} m)\n", closures, with.ate,
             without.ate);
  // measured: 1 closure (the map agrees with the loop afterwards), ATE 0.079 m against 1.438 m; with the
  // pose graph alone (no fusion, no global bundle adjustment) it was 3 closures and 0.231 m
  CHECK(closures >= 1);
  CHECK(with.loops.closures == closures);
  CHECK(with.loops.implausible == 0);  // a true loop asks for no more than odometry drifts
  CHECK(with.ate < 0.12);
  CHECK(with.ate < 0.1 * without.ate);
}

TEST_CASE("loop closer: a street of identical blocks verifies false loops, and none is closed") {
  // `rgbl demo --scenario repeated`: every 100 m the same buildings, cars, trees and markings, so the
  // scan and the image 100 m on match the earlier ones as well as a true revisit would
  const Lap lap = generate(rgbl::scenario_options("repeated", 1));
  REQUIRE(lap.frames.size() == 300);
  const Run guarded = track(lap, true);
  for (const auto& r : guarded.results) CHECK(r.state == rgbl::TrackState::Ok);
  const rgbl::LoopClosingStats& s = guarded.loops;
  fmt::print("identical blocks: {} places verified of {} candidates, {} refused as more than odometry drifts, {} "
             "closures, ATE {:.3f} m\n",
             s.verified, s.candidates, s.implausible, s.closures, guarded.ate);
  // the scene does fool place recognition and verification (measured: 66 candidates, 9 verified, all
  // refused: each would have moved the map 100, 200 or 300 m after as many metres driven)
  CHECK(s.verified >= 5);
  CHECK(s.implausible == s.verified);
  CHECK(s.consistent == 0);
  CHECK(s.closures == 0);

  // Without the odometry bound two of them pass the 3-keyframe consistency check and are closed, which
  // wrecks the map (measured: ATE 89.9 m against 0.270 m): what the bound is for. (With seeds 2 and 3
  // the consistency check alone refuses them; this seed is the one that gets through it.)
  rgbl::LoopClosingOptions unbounded;
  unbounded.max_drift_percent = 1e6;
  unbounded.max_drift_deg_per_100m = 1e6;
  const Run fooled = track(lap, unbounded);
  int false_closures = 0;
  for (const auto& r : fooled.results) {
    if (!r.loop_closure) continue;
    const auto& c = *r.loop_closure;
    const double apart = (lap.truth[c.frame_index].translation() - lap.truth[c.matched_frame_index].translation()).norm();
    CAPTURE(c.frame_index, c.matched_frame_index, apart);
    CHECK(apart > 90.0);  // one or two blocks apart: the same-looking place, not the same place
    ++false_closures;
  }
  fmt::print("  without the bound: {} false closures, ATE {:.3f} m\n", false_closures, fooled.ate);
  CHECK(false_closures >= 1);
  CHECK(fooled.ate > 10.0 * guarded.ate);
}
