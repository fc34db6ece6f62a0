// Tracking failures on the real KITTI excerpt (sequence 04, camera 0, LiDAR depth): black frames, a
// dropped scan and a sudden jump in the images. The System must report the state of every frame,
// never throw, and keep every frame in the trajectory with the lost ones marked.
#include "reliability/failure_run.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>

using rgbl::test::check_complete;
using rgbl::test::frames;
using rgbl::test::relative_error;
using rgbl::test::run;
using rgbl::test::states;
using rgbl::test::Outcome;

TEST_CASE("black frames in the middle: lost while black, relocalised right after, every frame recorded") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  auto steps = frames(0, 29);
  for (std::size_t i = 12; i <= 14; ++i) steps[i].black = true;
  const Outcome o = run(*sequence, steps);
  INFO(states(o));
  check_complete(o);
  for (std::size_t i = 0; i < 12; ++i) CHECK(o.results[i].state == rgbl::TrackState::Ok);
  for (std::size_t i = 12; i <= 14; ++i) {
    CHECK(o.results[i].state == rgbl::TrackState::Lost);
    CHECK(o.results[i].keypoints == 0);
  }
  for (std::size_t i = 15; i < o.results.size(); ++i) CHECK(o.results[i].state == rgbl::TrackState::Ok);
  // Relocalised into the same map: the pose after the gap agrees with ground truth.
  CHECK(relative_error(o, 29) < 1.0);
}

TEST_CASE("a dropped scan (empty) is a frame without depth: tracking continues on the map") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  auto steps = frames(0, 24);
  steps[10].drop_scan = true;
  steps[11].drop_scan = true;
  const Outcome o = run(*sequence, steps);
  INFO(states(o));
  check_complete(o);
  CHECK(o.results[10].keypoints_with_depth == 0);
  CHECK(o.results[11].keypoints_with_depth == 0);
  for (const auto& r : o.results) CHECK(r.state == rgbl::TrackState::Ok);
  CHECK(relative_error(o, 24) < 1.0);
}

TEST_CASE("a sudden jump of 20 frames: the run completes and the jump is reported") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  auto steps = frames(0, 14);
  const auto after = frames(35, 50);
  steps.insert(steps.end(), after.begin(), after.end());
  const Outcome o = run(*sequence, steps);
  INFO(states(o));
  check_complete(o);
  for (std::size_t i = 0; i < 15; ++i) CHECK(o.results[i].state == rgbl::TrackState::Ok);
  WARN(states(o));
}
