// Loop closing on the simulator, where the truth says which places are the same: on the loop driven
// twice every closure must pair frames of one place and closing must pay off on the whole trajectory;
// on a street of identical blocks, built to fool it, no loop may be closed.

#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/sim/scenarios.hpp"
#include "rgbl/sim/synthetic.hpp"
#include "mapped_drive.hpp"
#include "sim_frames.hpp"
#include "support/pose_error.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
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
    l.frames.push_back(rgbl::test::render_frame(generator, i));
    l.truth.push_back(generator.pose(i));
  }
  return l;
}

// One lap of a 79 m loop (`rgbl demo --path loop --frames 80 --seed S`): the demo shrinks the loop so
// that 80 frames drive it once.
Lap one_lap(std::uint64_t seed) {
  rgbl::SyntheticOptions options;
  options.frames = 80;
  options.seed = seed;
  options.path.kind = rgbl::PathKind::loop;
  options.path.loop_corner_radius = 79.0 * options.step() / (2.0 * std::numbers::pi);
  return generate(options);
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
  std::vector<double> error;  // per fed frame, m, in the first camera's frame (no alignment)
  double ate = 0.0;
  std::vector<Eigen::Isometry3d> estimate;  // per fed frame, the written (corrected) pose
};

// Tracks the lap's frames `fed` (all when empty) in that order.
// register_gaps, register_lost: the tracker's own registrations across a gap in the frames and of a
// lost frame (TrackerOptions).
// lidar_pair: keyframes tied by their scans' registration in BA (KeyframePairOptions::lidar_sigma_*,
// on by default).
Run track(const Lap& lap, const rgbl::LoopClosingOptions& loop_closing, std::vector<std::size_t> fed = {},
          bool register_gaps = true, bool register_lost = true, bool lidar_pair = true) {
  if (fed.empty()) {
    for (std::size_t i = 0; i < lap.frames.size(); ++i) fed.push_back(i);
  }
  rgbl::SystemOptions options;
  options.loop_closing = loop_closing;
  options.tracker.register_gaps = register_gaps;
  options.tracker.register_lost = register_lost;
  if (!lidar_pair) options.mapping.pairs.lidar_sigma_translation = 0.0;
  const rgbl::test::Mapped m = rgbl::test::track_frames(
      lap.calibration, fed.size(), [&](std::size_t k) -> const rgbl::FrameInput& { return lap.frames[fed[k]]; },
      options);
  const auto trajectory = m.system->trajectory();
  REQUIRE(trajectory.size() == fed.size());
  Run run{m.results, m.system->loop_statistics(), {}, 0.0, {}};
  std::vector<Eigen::Isometry3d> estimate, truth;
  for (std::size_t k = 0; k < fed.size(); ++k) {
    estimate.push_back(trajectory[k].T_world_cam);
    truth.push_back(lap.truth[fed[k]]);
    run.error.push_back((estimate.back().translation() - truth.back().translation()).norm());
  }
  run.ate = rgbl::absolute_trajectory_error(estimate, truth).translation.rmse;
  run.estimate = std::move(estimate);
  return run;
}

// The frames fed for the map-merging tests: frames 60-79 of the first lap (2 s, 20 m) left out.
std::vector<std::size_t> without_first_lap_gap(const Lap& lap) {
  std::vector<std::size_t> fed;
  for (std::size_t i = 0; i < lap.frames.size(); ++i) {
    if (i < 60 || i >= 80) fed.push_back(i);
  }
  return fed;
}

Run track(const Lap& lap, bool loop_closing, bool lidar_pair = true) {
  rgbl::LoopClosingOptions options;
  options.enabled = loop_closing;
  return track(lap, options, {}, true, true, lidar_pair);
}

// What a closure corrects is drift, and with the scans tying keyframes (the default) these laps
// hardly drift: one lap of 79 m ends 0.013-0.025 m ATE without loop closing (seeds 1-3), where a
// closure's own relative pose is off by 0.01-0.06 m; two laps 0.06 m (docs/accuracy.md, "Keyframes
// tied by their scans"). So the two tests of a closure's gain track without that pair, as the drive
// of a LiDAR whose scans do not register would, and the lap with it is checked for its drift alone.
constexpr bool kDrifting = false;

// Every frame tracked ok and every closure true: the relative pose between its two frames in the
// written trajectory agrees with the truth's, whichever distance apart they are (a false closure ties
// two places tens of metres apart together), and none before frame `first` (where the drive first
// comes back). Frames as fed in lap order. The number of closures.
int check_closures(const Lap& lap, const Run& run, std::size_t first) {
  int closures = 0;
  for (const auto& r : run.results) {
    CHECK(r.state == rgbl::TrackState::Ok);
    if (!r.loop_closure) continue;
    ++closures;
    const auto& c = *r.loop_closure;
    const std::size_t i = c.frame_index, j = c.matched_frame_index;
    const double apart = (lap.truth[i].translation() - lap.truth[j].translation()).norm();
    const auto [error_m, error_deg] = rgbl::test::relative_error(lap.truth[i], lap.truth[j], run.estimate[i], run.estimate[j]);
    CAPTURE(i, j, apart, error_m, error_deg, c.correction_m, c.correction_deg);
    fmt::print("closure: frame {} with {}, {:.1f} m apart in the truth, relative pose off by {:.3f} m / {:.2f} deg\n",
               i, j, apart, error_m, error_deg);
    CHECK(error_m < 0.3);
    CHECK(error_deg < 1.5);
    CHECK(i >= first);
  }
  return closures;
}

}  // namespace

TEST_CASE("loop closer: two laps of the simulator's loop are closed where the places are the same") {
  const Lap& lap = two_laps();
  const Run with = track(lap, true, kDrifting);
  const Run without = track(lap, false, kDrifting);
  // The second lap comes back into view of frame 0's place 9 m before it (frame 91 sees it ahead: 8.9 m
  // apart in the truth, matched since the ratio test no longer counts a point's unfused copies as rivals)
  const int closures = check_closures(lap, with, 90);
  fmt::print("two laps of a 100 m loop: {} closures, ATE {:.3f} m (without loop closing {:.3f} m)\n", closures, with.ate,
             without.ate);
  // measured: 1 closure, ATE 0.043 m against 0.161 m without closing (0.042 m with the global bundle
  // adjustment, off by default). Before keyframes kept the tracked motion (2026-11-28): 2 closures,
  // 0.056 m against 0.398 m; before the road tied local BA's keyframes: 0.054 m against 1.438 m
  // (docs/loop-closing.md). Since keyframes come when the established landmarks thin out: frame 92
  // with frame 0, ATE 0.039 m against 0.236 m.
  CHECK(closures >= 1);
  CHECK(with.loops.closures == closures);
  CHECK(with.loops.implausible == 0);  // a true loop asks for no more than odometry drifts
  CHECK(with.ate < 0.08);
  CHECK(with.ate < 0.4 * without.ate);
}

TEST_CASE("loop closer: two laps closed when the second is driven a lane to the left") {
  // `rgbl demo --path loop --frames 201 --laps 2 --lap-offset -3.3`: the places are the same, the
  // viewpoints 3.3 m apart (not repeated to within a frame's step as on the plain loop)
  rgbl::SyntheticOptions options;
  options.frames = 201;
  options.path.kind = rgbl::PathKind::loop;
  options.path.loop_laps = 2;
  options.path.loop_lap_offset = -3.3;
  const Lap lap = generate(options);
  const Run with = track(lap, true, kDrifting);
  const int closures = check_closures(lap, with, 90);
  fmt::print("two laps of a 100 m loop, the second a lane to the left: {} closures, ATE {:.3f} m\n", closures,
             with.ate);
  // measured: 2 closures (frame 97 with frame 0 by the bag of words, 191 with 80 by Scan Context),
  // ATE 0.108 m (0.054 m on the same track; 1.438 m there without loop closing); since keyframes keep
  // the tracked motion (2026-11-28): 1 closure, 0.059 m; since keyframes come when the established
  // landmarks thin out: frame 97 with frame 18, 17.8 m apart, 0.043 m. Tracked without the scans' pair
  // (kDrifting) since the tracker's Cauchy weights (2026-12-06): with the pair the laps drift so little
  // that every loop found only confirms the map (e.g. keyframe 22 with 1, 0.048 m off: no correction;
  // ATE 0.029 m), which tests nothing of the lane. Without it: 1 closure, ATE 0.038 m.
  CHECK(closures >= 1);
  CHECK(with.loops.implausible == 0);
  CHECK(with.ate < 0.16);
}

TEST_CASE("loop closer: a bag of words alone closes the two laps (a depth source without a LiDAR scan)") {
  // Scan Context off: the candidates come from the ORB descriptors through the shipped vocabulary,
  // trained on real KITTI images, none of them the simulator's
  const Lap& lap = two_laps();
  rgbl::LoopClosingOptions options;
  options.places.methods = {"bow"};
  // without the scans' keyframe pairs too, as such a source has none (with them these laps hardly
  // drift, and the bag of words found no closure: 0.034 m)
  const Run with = track(lap, options, {}, true, true, kDrifting);
  const int closures = check_closures(lap, with, 90);
  fmt::print("two laps of a 100 m loop, bag of words only: {} closures, ATE {:.3f} m, {} candidates verified for {} "
             "keyframes\n",
             closures, with.ate, with.loops.candidates, with.loops.keyframes);
  CHECK(closures >= 1);
  CHECK(with.loops.implausible == 0);
  CHECK(with.ate < 0.08);
}

TEST_CASE("loop closer: a drive that ends where it began is closed at its last keyframe") {
  // one lap of a 79 m loop (`rgbl demo --path loop --frames 80`): only the last keyframes see the
  // first ones' places, the keyframes before them are behind the start, so the matched keyframe's
  // neighbours confirm the loop. Three seeds: one lap's gain is one sample of a chaotic run (seed 1
  // alone, with/without at 5 feature counts: 0.58-0.90 on main before the occlusion filter).
  double log_ratio = 0.0;
  for (const std::uint64_t seed : {1, 2, 3}) {
    CAPTURE(seed);
    const Lap lap = one_lap(seed);
    const Run with = track(lap, true, kDrifting);
    const Run without = track(lap, false, kDrifting);
    const Run tied = track(lap, false);  // the default: keyframes tied by their scans, no loop closing
    fmt::print("one lap of a 79 m loop, seed {}, keyframes tied by their scans, no loop closing: ATE {:.3f} m\n", seed,
               tied.ate);
    CHECK(tied.ate < 0.04);
    // seed 3 closes at frame 68, with frame 0's place 10.7 m ahead in view
    const int closures = check_closures(lap, with, 65);
    fmt::print("one lap of a 79 m loop, seed {}: {} closures, ATE {:.3f} m (without loop closing {:.3f} m)\n", seed,
               closures, with.ate, without.ate);
    CHECK(closures == 1);
    CHECK(with.loops.implausible == 0);
    CHECK(with.ate < without.ate);
    log_ratio += std::log(with.ate / without.ate) / 3.0;
  }
  // measured (seeds 1, 2, 3): 0.046 / 0.060, 0.025 / 0.073, 0.034 / 0.056 m, a geometric mean of 0.54
  // (0.55 before returns behind foreground edges were dropped). Seed 1 alone, since keyframes come when
  // the established landmarks thin out: 0.024 m against 0.068 m.
  CHECK(std::exp(log_ratio) < 0.7);
}

TEST_CASE("loop closer: the scans measure a short loop again, and a map that hardly drifted is left as it is") {
  // One lap of 79 m, seeds 1 and 3, keyframes tied by their scans (the default): the map drifts a few
  // centimetres, but the images' loop measurement leans on the first keyframes' landmarks and is off
  // by about 0.2 m, so it closes the loop and moves the map by as much (measured: ATE 0.018 -> 0.035 m
  // and 0.017 -> 0.027 m). The two keyframes' scans, registered from it, measure the loop 0.035 and
  // 0.050 m from the map: it only confirms the map.
  for (const std::uint64_t seed : {1, 3}) {
    CAPTURE(seed);
    const Lap lap = one_lap(seed);
    rgbl::LoopClosingOptions images_only;
    images_only.scans.enabled = false;
    const Run scans = track(lap, rgbl::LoopClosingOptions{});
    const Run images = track(lap, images_only);
    fmt::print("one lap of a 79 m loop, seed {}: loops measured by the scans {} closures, {} confirming, ATE {:.3f} m; "
               "by the images alone {} closures, ATE {:.3f} m\n",
               seed, scans.loops.closures, scans.loops.confirming, scans.ate, images.loops.closures, images.ate);
    CHECK(images.loops.closures == 1);
    CHECK(scans.loops.closures == 0);
    CHECK(scans.loops.confirming >= 1);
    CHECK(scans.loops.scan_refined >= 3);  // the loop and the two keyframe pairs that confirmed it
    CHECK(scans.loops.scan_kept == 0);
    CHECK(images.loops.scan_refined == 0);
    CHECK(scans.ate < 0.8 * images.ate);
    CHECK(scans.ate < 0.025);
  }
}

TEST_CASE("loop closer: the global bundle adjustment holds keyframes the shared landmarks cannot place") {
  // one lap of 79 m, seed 3, with the (optional) global BA: before keyframes with too little shared
  // evidence were held, frames 20-35 ended 1.4-1.6 m off (on the first lap of two, same seed, the
  // keyframes of frames 18 and 26 shared 2 observations each with the rest of the map at the
  // closure); now such keyframes are held and follow their parent. Since keyframes come when the
  // established landmarks thin out (2026-11-28) no keyframe of this lap falls under the default bar
  // of 30 shared observations, so the hold is exercised with a bar of 400 as well. Since loops are
  // measured again by the scans this lap's loop is 0.05 m from the map and only confirms it: without
  // a correction bar the loop is closed all the same, so the BA runs.
  const Lap lap = one_lap(3);
  for (const int min_shared : {30, 400}) {
    rgbl::LoopClosingOptions with_ba;
    with_ba.global_ba = true;
    with_ba.min_correction_m = 0.0;
    with_ba.min_correction_deg = 0.0;
    with_ba.global_ba_min_shared = min_shared;
    const Run run = track(lap, with_ba);
    const int closures = check_closures(lap, run, 60);  // frame 67 sees the start 11.5 m ahead
    const double worst = *std::max_element(run.error.begin(), run.error.end());
    int held = 0;
    for (const auto& r : run.results) held += r.loop_closure ? r.loop_closure->global_ba_held : 0;
    fmt::print("one lap of 79 m, seed 3, global BA, held under {} shared: {} closures, {} keyframes held, worst frame "
               "{:.3f} m, ATE {:.3f} m\n",
               min_shared, closures, held, worst, run.ate);
    // measured: 1 closure, 4 keyframes held, worst frame 0.509 m (`rgbl run` of the same lap without the
    // BA: 0.446 m), ATE 0.147 m (0.345 m before keyframes were held); since the road and the tracked
    // motion tie local BA's keyframes (2026-11-28): 3 held, worst frame 0.234 m, ATE 0.061 m; since the
    // global BA has the same pairs: 0.150 m, 0.047 m. Since keyframes come when the established
    // landmarks thin out: closed at frame 67, 0 held, 0.273 m, 0.031 m; under 400: 12 held, 0.359 m,
    // 0.057 m. Since the scans measure the loop (closed at no bar): 0 held, 0.062 m, 0.015 m; under
    // 400: 13 held, 0.051 m, 0.013 m
    CAPTURE(min_shared);
    CHECK(closures == 1);
    if (min_shared > 30) CHECK(held >= 1);
    CHECK(worst < 0.8);
    CHECK(run.ate < 0.25);
  }
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
  // the scene does fool place recognition and verification (measured: 94 candidates from Scan Context
  // and the bag of words, 9 verified, all
  // refused: each would have moved the map 100, 200 or 300 m after as many metres driven; 2026-11-28:
  // 93 candidates, 10 verified, all refused; with keyframes when the established landmarks thin out:
  // 84 candidates, 12 verified, all refused; since keypoints map pixel centre to pixel centre across
  // pyramid levels: 29 candidates, 3 verified, all refused; without the bound one is still closed, below)
  CHECK(s.verified >= 1);
  CHECK(s.implausible == s.verified);
  CHECK(s.consistent == 0);
  CHECK(s.closures == 0);

  // Without the odometry bound two of them pass the 3-keyframe consistency check and are closed, which
  // wrecks the map (measured: ATE 89.9 m against 0.270 m; 2026-11-28: 5 closures, 84.3 m against
  // 0.110 m; then 4 closures, 78.9 m against 0.070 m): what the bound is for. (With seeds 2 and 3
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
    // a block apart or more (measured 2026-11-28: 81 m, frames 205 and 124, among 5): a same-looking
    // place, not the same place
    CHECK(apart > 50.0);
    ++false_closures;
  }
  fmt::print("  without the bound: {} false closures, ATE {:.3f} m\n", false_closures, fooled.ate);
  CHECK(false_closures >= 1);
  CHECK(fooled.ate > 10.0 * guarded.ate);
}

TEST_CASE("map merging: a jump on the first lap starts a new map, which the second lap merges into the first") {
  const Lap& lap = two_laps();
  // frames 0-59, then 80-200: 2 s and 20 m of the first lap missing, so tracking is lost and a new map
  // starts at the motion model's guess; the second lap passes the first map's places (frames 100-159)
  const std::vector<std::size_t> fed = without_first_lap_gap(lap);
  // Bridging (the scans registered across the gap) would merge the maps at once (the next test): off
  // here, so that the second lap's revisit merges them; and the tracker registers neither the gap nor
  // the lost frames (it would anchor the new map where the scans put it, test_reliability), so that the
  // new map starts at the constant-velocity guess, as after a gap without scans.
  rgbl::LoopClosingOptions revisit;
  revisit.bridge.enabled = false;
  rgbl::LoopClosingOptions separate;
  separate.merge_maps = false;
  const Run merged = track(lap, revisit, fed, false, false);
  const Run apart = track(lap, separate, fed, false, false);

  int new_maps = 0;
  std::optional<std::size_t> merge_at;  // fed index
  for (std::size_t k = 0; k < fed.size(); ++k) {
    const auto& r = merged.results[k];
    new_maps += r.new_map ? 1 : 0;
    if (!r.loop_closure || !r.loop_closure->merged) continue;
    CHECK_FALSE(merge_at);
    merge_at = k;
    // the two frames see one place: their written relative pose is the truth's (frames as fed)
    const std::size_t a = r.loop_closure->frame_index, b = r.loop_closure->matched_frame_index;
    REQUIRE(a < fed.size());
    REQUIRE(b < fed.size());
    const auto [error_m, error_deg] = rgbl::test::relative_error(lap.truth[fed[a]], lap.truth[fed[b]], merged.estimate[a], merged.estimate[b]);
    CAPTURE(fed[a], fed[b], error_m, error_deg);
    fmt::print("merge: frame {} with {}, {:.1f} m apart in the truth, relative pose off by {:.3f} m / {:.2f} deg\n",
               fed[a], fed[b], (lap.truth[fed[a]].translation() - lap.truth[fed[b]].translation()).norm(), error_m,
               error_deg);
    CHECK(error_m < 0.3);
    CHECK(error_deg < 1.5);
    CHECK(fed[b] < 60);  // in the first map
  }
  CHECK(new_maps == 1);
  REQUIRE(merge_at);
  CHECK(merged.loops.merges == 1);
  CHECK(apart.loops.merges == 0);
  const auto worst = [&](std::size_t from, std::size_t to) {
    return *std::max_element(merged.error.begin() + static_cast<std::ptrdiff_t>(from),
                             merged.error.begin() + static_cast<std::ptrdiff_t>(std::min(to, fed.size())));
  };
  const double worst_after = worst(*merge_at, *merge_at + 25);
  fmt::print("a jump on the first lap: new map, merged at frame {} (error there {:.3f} m, without merging {:.3f} m; "
             "at most {:.3f} m over the next 25 frames, {:.3f} m to the end); ATE {:.3f} m, without merging "
             "{:.3f} m\n",
             fed[*merge_at], merged.error[*merge_at], apart.error[*merge_at], worst_after,
             worst(*merge_at, fed.size()), merged.ate, apart.ate);
  // measured: see docs/loop-closing.md (map merging); the error grows again where the second lap
  // re-enters the new map's own start (frames 85-100), placed by the guess and never tied by a loop
  CHECK(merged.error[*merge_at] < 0.15);
  CHECK(apart.error[*merge_at] > 1.0);
  CHECK(worst_after < 0.3);
  CHECK(merged.ate < 0.5 * apart.ate);
}

TEST_CASE("map merging: the new map after a jump is bridged to the old one by registering the scans across the gap") {
  const Lap& lap = two_laps();
  const std::vector<std::size_t> fed = without_first_lap_gap(lap);  // the jump of the test above
  // the new map started at the constant-velocity guess, as above: the bridge alone moves it
  rgbl::LoopClosingOptions separate;
  separate.merge_maps = false;
  const Run bridged = track(lap, rgbl::LoopClosingOptions{}, fed, false, false);
  const Run apart = track(lap, separate, fed, false, false);
  std::optional<std::size_t> new_map, bridge_at;  // fed indices
  for (std::size_t k = 0; k < fed.size(); ++k) {
    const auto& r = bridged.results[k];
    if (r.new_map) {
      CHECK_FALSE(new_map);
      new_map = k;
    }
    if (!r.loop_closure || !r.loop_closure->bridged) continue;
    CHECK_FALSE(bridge_at);
    bridge_at = k;
    CHECK(r.loop_closure->merged);
    // the two keyframes' written relative pose is the truth's
    const std::size_t a = r.loop_closure->frame_index, b = r.loop_closure->matched_frame_index;
    REQUIRE(a < fed.size());
    REQUIRE(b < fed.size());
    const auto [error_m, error_deg] =
        rgbl::test::relative_error(lap.truth[fed[a]], lap.truth[fed[b]], bridged.estimate[a], bridged.estimate[b]);
    CAPTURE(fed[a], fed[b], error_m, error_deg);
    fmt::print("bridge: frame {} onto {}, {:.1f} m apart in the truth, relative pose off by {:.3f} m / {:.2f} deg\n",
               fed[a], fed[b], (lap.truth[fed[a]].translation() - lap.truth[fed[b]].translation()).norm(), error_m,
               error_deg);
    CHECK(error_m < 0.15);
    CHECK(error_deg < 1.0);
    CHECK(fed[b] < 60);  // the old map's last keyframe
  }
  // the bridge comes with the new map's first keyframe, and is the only merge the run needs
  REQUIRE(new_map);
  REQUIRE(bridge_at);
  CHECK(*bridge_at == *new_map);
  CHECK(bridged.loops.bridges == 1);
  CHECK(bridged.loops.merges == 1);
  const double worst_after = *std::max_element(bridged.error.begin() + static_cast<std::ptrdiff_t>(*bridge_at),
                                               bridged.error.end());
  // The old map's own error, before the gap: the second lap re-tracks that stretch in the same map and
  // repeats it (with the ring plane fit: 0.317 m at frame 54 and again at frame 162), which no bridge
  // can mend.
  const auto gap = std::adjacent_find(fed.begin(), fed.end(), [](std::size_t a, std::size_t b) { return b != a + 1; });
  const auto before_gap = gap == fed.end() ? fed.size() : static_cast<std::size_t>(gap - fed.begin()) + 1;
  const double worst_before =
      *std::max_element(bridged.error.begin(), bridged.error.begin() + static_cast<std::ptrdiff_t>(before_gap));
  fmt::print("a jump on the first lap bridged at frame {}: error there {:.3f} m (without merging {:.3f} m), at most "
             "{:.3f} m to the end (at most {:.3f} m before the gap); ATE {:.3f} m, without merging {:.3f} m\n",
             fed[*bridge_at], bridged.error[*bridge_at], apart.error[*bridge_at], worst_after, worst_before,
             bridged.ate, apart.ate);
  // measured: see docs/loop-closing.md (bridging a gap)
  CHECK(bridged.error[*bridge_at] < 0.2);
  CHECK(apart.error[*bridge_at] > 0.5);
  // after the bridge no frame is further off than the old map was before the gap, give or take the
  // bridge's own 0.1 m (without merging: 2.6 m)
  CHECK(worst_after < worst_before + 0.1);
  CHECK(worst_after < 0.4);
  CHECK(bridged.ate < 0.2 * apart.ate);
}

namespace {

// The lap's frames in order, frames first..last left out (they never arrive; their time passes).
std::vector<std::size_t> skipping(const Lap& lap, std::size_t first, std::size_t last) {
  std::vector<std::size_t> fed;
  for (std::size_t i = 0; i < lap.frames.size(); ++i) {
    if (i < first || i > last) fed.push_back(i);
  }
  return fed;
}

}  // namespace

TEST_CASE("a gap in a bend along a hedge: the scans registered across it place the next frame, not a look-alike") {
  // `rgbl demo --scenario foliage --seed 2`: a curve along a dense hedge; frames 30-39 (1 s) never
  // arrive. The car turns 14 deg in the gap, so the constant-velocity guess is 14 deg and 1.2 m off,
  // and from it the images find the hedge 10 m along, 71 inliers (scripts/jump-table.sh found this).
  const Lap lap = generate(rgbl::scenario_options("foliage", 2));
  const std::vector<std::size_t> fed = skipping(lap, 30, 39);
  const std::size_t after = 30;  // fed index of frame 40
  rgbl::LoopClosingOptions loop_closing;
  loop_closing.enabled = false;  // the tracker alone
  const Run registered = track(lap, loop_closing, fed);
  const Run guessed = track(lap, loop_closing, fed, false, false);
  const auto worst_after = [&](const Run& run) {
    return *std::max_element(run.error.begin() + static_cast<std::ptrdiff_t>(after), run.error.end());
  };
  fmt::print("a 1 s gap in a bend along a hedge: frame 40 {:.3f} m off, at most {:.3f} m after, ATE {:.3f} m; without "
             "the registration {:.3f} m, {:.3f} m, ATE {:.3f} m\n",
             registered.error[after], worst_after(registered), registered.ate, guessed.error[after],
             worst_after(guessed), guessed.ate);
  for (const auto& r : registered.results) CHECK(r.state == rgbl::TrackState::Ok);
  for (std::size_t k = 0; k < fed.size(); ++k) {
    CHECK(registered.results[k].gap == (k == after));
    CHECK(registered.results[k].gap_registered == (k == after));
    CHECK_FALSE(guessed.results[k].gap);
  }
  // measured: 0.05 m ATE over the run (0.04 m without the gap); 8.4 m without the registration
  CHECK(registered.error[after] < 0.2);
  CHECK(worst_after(registered) < 0.3);
  CHECK(registered.ate < 0.1);
  // Without the registration the images alone took the look-alike (8.4 m) until 2026-12-05; since the
  // first keyframe's landmarks are culled like any other's they find frame 40 here (0.14 m), and with
  // the ring plane fit on they take the hedge again (10.7 m): a chaotic outcome, printed, not asserted.
}

TEST_CASE("braking in a gap, then no images: the lost frames keep the scans' motion, not the speed from before") {
  // `rgbl demo --scenario traffic --seed 1`: frames 30-39 (1 s) never arrive while the car brakes for
  // the traffic ahead (0.7 m a frame before the gap, about 0.3 m after), and the next five images are
  // black; their scans arrive. Frame 40's scan registers across the gap (TrackerOptions::register_gaps),
  // then each lost frame's onto the one before (register_lost), and the velocity comes from them. With
  // register_lost off the lost frames go on at the speed from before the gap, and so does the new map
  // started after them.
  Lap lap = generate(rgbl::scenario_options("traffic", 1));
  for (std::size_t i = 40; i <= 44; ++i) {
    lap.frames[i].images[0] = cv::Mat::zeros(lap.frames[i].images[0].size(), lap.frames[i].images[0].type());
  }
  const std::vector<std::size_t> fed = skipping(lap, 30, 39);
  const std::size_t after = 30;  // fed index of frame 40
  rgbl::LoopClosingOptions loop_closing;
  loop_closing.enabled = false;  // the tracker alone
  const Run placed = track(lap, loop_closing, fed);
  const Run stale = track(lap, loop_closing, fed, true, false);
  const auto worst = [&](const Run& run, std::size_t from, std::size_t to) {
    return *std::max_element(run.error.begin() + static_cast<std::ptrdiff_t>(from),
                             run.error.begin() + static_cast<std::ptrdiff_t>(to));
  };
  fmt::print("braking in a 1 s gap, then 5 black frames: lost frames at most {:.3f} m off, the first with images "
             "{:.3f} m, at most {:.3f} m after it, ATE {:.3f} m; at the speed from before the gap {:.3f} m, {:.3f} m, "
             "{:.3f} m, ATE {:.3f} m\n",
             worst(placed, after, after + 5), placed.error[after + 5], worst(placed, after + 6, fed.size()), placed.ate,
             worst(stale, after, after + 5), stale.error[after + 5], worst(stale, after + 6, fed.size()), stale.ate);
  CHECK(placed.results[after].gap_registered);
  for (std::size_t k = after; k < after + 5; ++k) {
    INFO("frame " << fed[k]);
    CHECK(placed.results[k].state == rgbl::TrackState::Lost);
    CHECK(placed.results[k].lost_registered);
    CHECK_FALSE(stale.results[k].lost_registered);
  }
  for (std::size_t k = after + 5; k < fed.size(); ++k) CHECK(placed.results[k].state == rgbl::TrackState::Ok);
  CHECK(worst(placed, after, after + 5) < 0.3);
  // The first frame with images again (frame 45) relocalises on 151 inliers, none of those with depth
  // nearer than 15 m and 80 % of them 19-34 m ahead (the map's nearer points lie behind it), where
  // the camera's height and pitch nearly trade for each other: it comes out 0.31 m high (0.23 m with
  // the ring plane fit off). The next frame, on 443 inliers, is 0.06 m off.
  CHECK(placed.results[after + 5].relocalised);
  CHECK(placed.error[after + 5] < 0.4);
  CHECK(worst(placed, after + 6, fed.size()) < 0.15);  // measured 0.082 m (0.207 m with the fit off)
  CHECK(worst(stale, after, after + 5) > 1.0);  // for the record: what the stale speed does
}
