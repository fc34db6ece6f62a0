// Local mapping in its own thread: the tests CI also runs under ThreadSanitizer (label `threaded`,
// scripts/sanitize.sh). Keep them short: TSan makes them ~10x slower.
#include "reliability/failure_run.hpp"
#include "tracking/kitti_run.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>

TEST_CASE("threaded mapping: seq 04 still tracked throughout") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  rgbl::SystemOptions options;
  options.threaded_mapping = true;
  const auto s = rgbl::test::run_sequence(*sequence, 0, 51, options);
  INFO("ATE " << s.ate_rmse << " m, drift " << s.drift_percent << " %");
  CHECK(s.frames == 51);
  // Never lost. How many frames are ok rather than weak depends on scheduling, not on the code: when
  // mapping lags (a loaded machine, a sanitizer) a frame meets a map without its newest keyframes and
  // is honestly weak (31 of 51 ok under AddressSanitizer on a loaded 2-core machine), so that split is
  // not asserted here; the inline runs assert it exactly.
  CHECK(s.with_pose == 51);
  // Not bit-reproducible (keyframes depend on mapping progress): a looser bound than inline.
  CHECK(s.ate_rmse <= 0.2);
}

TEST_CASE("threaded mapping: black frames and a dropped scan, every frame recorded") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  auto steps = rgbl::test::frames(0, 24);
  steps[8].drop_scan = true;
  for (std::size_t i = 12; i <= 13; ++i) steps[i].black = true;
  const auto o = rgbl::test::run(*sequence, steps, true);
  INFO(rgbl::test::states(o));
  rgbl::test::check_complete(o);
  CHECK(o.results[12].state == rgbl::TrackState::Lost);
  CHECK(o.results[13].state == rgbl::TrackState::Lost);
  CHECK(rgbl::has_pose(o.results.back().state));  // ok, or weak while mapping lags
}

TEST_CASE("threaded mapping: a jump of 20 frames starts a new map while mapping runs") {
  const auto sequence = rgbl::test::kitti_seq04();
  if (!sequence) return;
  const auto o = rgbl::test::run(*sequence, rgbl::test::jump(0, 14, 35, 44), true);
  INFO(rgbl::test::states(o));
  rgbl::test::check_complete(o);
  CHECK(o.results[15].state == rgbl::TrackState::Lost);
  int new_maps = 0;
  for (const auto& r : o.results) new_maps += r.new_map ? 1 : 0;
  CHECK(new_maps == 1);
  CHECK(rgbl::has_pose(o.results.back().state));  // ok, or weak while mapping lags
}
