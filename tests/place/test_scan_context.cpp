#include "rgbl/place/scan_context.hpp"

#include "rgbl/core/error.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace {

std::vector<rgbl::LidarPoint> rotated(const std::vector<rgbl::LidarPoint>& scan, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  std::vector<rgbl::LidarPoint> out = scan;
  for (auto& p : out) {
    const double x = p.x, y = p.y;
    p.x = static_cast<float>(c * x - s * y);
    p.y = static_cast<float>(s * x + c * y);
  }
  return out;
}

rgbl::LidarPoint at(double range, double azimuth, double z) {
  return {static_cast<float>(range * std::cos(azimuth)), static_cast<float>(range * std::sin(azimuth)),
          static_cast<float>(z), 0.0F};
}

std::vector<rgbl::LidarPoint> scan04(int frame) {
  const auto dir = *rgbl::test::kitti_seq04();
  char name[16];
  std::snprintf(name, sizeof(name), "%06d.bin", frame);
  return rgbl::read_kitti_scan(dir / "velodyne" / name);
}

}  // namespace

TEST_CASE("scan context cells hold the highest point of each polar cell") {
  rgbl::ScanContextOptions options;  // 20 rings of 3.9 m from 2 m, 60 sectors of 6 deg, +2 m
  const double sector = 2.0 * std::numbers::pi / options.sectors;
  std::vector<rgbl::LidarPoint> scan{
      at(10.0, -std::numbers::pi + 0.5 * sector, -1.7),   // road: ring 2, sector 0
      at(10.5, -std::numbers::pi + 0.4 * sector, 1.3),    // a pole in the same cell: its top wins
      at(30.0, 0.25 * sector, 0.5),           // ring 7, sector 30 (just left of ahead)
      at(1.0, 0.0, 3.0),                      // nearer than min_range: the ego car
      at(90.0, 0.0, 3.0),                     // beyond max_range
      at(20.0, 0.0, -2.5),                    // below -height_offset: clamped to 0, still empty
      {std::nanf(""), 0.0F, 0.0F, 0.0F}};
  const rgbl::ScanContext c = rgbl::make_scan_context(scan, options);
  REQUIRE(c.rings() == 20);
  REQUIRE(c.sectors() == 60);
  CHECK(c.cell(2, 0) == Approx(3.3F));
  CHECK(c.cell(7, 30) == Approx(2.5F));
  int occupied = 0;
  for (int r = 0; r < c.rings(); ++r) {
    for (int s = 0; s < c.sectors(); ++s) occupied += c.cell(r, s) > 0.0F ? 1 : 0;
  }
  CHECK(occupied == 2);
  CHECK(c.ring_key()[2] == Approx(1.0 / 60.0));
  CHECK(c.ring_key()[7] == Approx(1.0 / 60.0));
  CHECK(c.ring_key()[0] == 0.0F);
}

TEST_CASE("scan context of a synthetic scene: each cell its highest point, the rest empty") {
  // Defaults: ring r holds ranges [2 + 3.9 r, 5.9 + 3.9 r) m, sector s azimuths [-180 + 6 s, -174 + 6 s)
  // deg. Every object is built in polar coordinates well inside its cells, so the expected value of every
  // cell is known without the descriptor's own arithmetic.
  const rgbl::ScanContextOptions options;
  const double deg = std::numbers::pi / 180.0;
  const auto range_in = [](int ring, double f) { return 2.0 + 3.9 * (ring + f); };  // f in (0, 1) across the ring
  const auto azimuth_in = [&](int sector, double f) { return (-180.0 + 6.0 * (sector + f)) * deg; };
  std::vector<rgbl::LidarPoint> scan;
  std::map<std::pair<int, int>, double> expected;  // (ring, sector) -> z + 2 m of the highest point

  // road 1.73 m below the sensor over rings 0..4 all round: 0.27
  for (int r = 0; r <= 4; ++r) {
    for (int s = 0; s < 60; ++s) {
      for (const double f : {0.2, 0.5, 0.8}) scan.push_back(at(range_in(r, f), azimuth_in(s, f), -1.73));
      expected[{r, s}] = 0.27;
    }
  }
  // a pole in ring 3, sector 10 (behind right), points every 10 cm from the road up to 2.5 m
  for (int i = 0; i <= 40; ++i) scan.push_back(at(range_in(3, 0.4), azimuth_in(10, 0.6), -1.5 + 0.1 * i));
  expected[{3, 10}] = 4.5;
  // a box over rings 1..2, sectors 20..22, top at 0.5 m, sides down to the road
  for (int r = 1; r <= 2; ++r) {
    for (int s = 20; s <= 22; ++s) {
      for (const double f : {0.1, 0.5, 0.9}) {
        for (const double z : {-1.5, -0.5, 0.5}) scan.push_back(at(range_in(r, f), azimuth_in(s, 1.0 - f), z));
      }
      expected[{r, s}] = 2.5;
    }
  }
  // a wall (an arc at 24 m: ring 5) across sectors 40..44, 1 m high
  for (int s = 40; s <= 44; ++s) {
    for (const double f : {0.05, 0.35, 0.65, 0.95}) {
      for (const double z : {-1.73, -0.5, 0.25, 1.0}) scan.push_back(at(24.0, azimuth_in(s, f), z));
    }
    expected[{5, s}] = 3.0;
  }
  // a ramp in ring 4, sector 50, its points out of height order: the maximum wins
  for (const double z : {-1.0, 0.7, -0.2, 0.3, -1.5}) scan.push_back(at(range_in(4, 0.5), azimuth_in(50, 0.5), z));
  expected[{4, 50}] = 2.7;
  // directly behind (y = 0, x < 0, azimuth +pi) at 40 m: ring 9, sector 0 (+pi wraps to -pi)
  scan.push_back({-40.0F, 0.0F, 0.0F, 0.0F});
  expected[{9, 0}] = 2.0;
  // nothing of these may show: a point 2.5 m below the sensor (clamped to 0), the ego car, beyond 80 m,
  // non-finite coordinates
  scan.push_back(at(range_in(7, 0.5), azimuth_in(5, 0.5), -2.5));
  scan.push_back(at(1.5, 0.3, 1.0));
  scan.push_back(at(85.0, 0.3, 1.0));
  scan.push_back({std::nanf(""), 10.0F, 0.0F, 0.0F});
  scan.push_back({10.0F, std::numeric_limits<float>::infinity(), 0.0F, 0.0F});
  scan.push_back({-30.0F, 30.0F, std::nanf(""), 0.0F});  // ring 10, sector 52: otherwise empty

  const rgbl::ScanContext c = rgbl::make_scan_context(scan, options);
  REQUIRE(c.rings() == 20);
  REQUIRE(c.sectors() == 60);
  int mismatches = 0;
  for (int r = 0; r < 20; ++r) {
    for (int s = 0; s < 60; ++s) {
      const auto it = expected.find({r, s});
      const double want = it == expected.end() ? 0.0 : it->second;
      if (c.cell(r, s) != Approx(want).margin(1e-5)) {
        ++mismatches;
        UNSCOPED_INFO("cell (" << r << ", " << s << "): " << c.cell(r, s) << ", expected " << want);
      }
    }
  }
  CHECK(mismatches == 0);
  CHECK(c.ring_key()[0] == Approx(1.0));
  CHECK(c.ring_key()[5] == Approx(5.0 / 60.0));
  CHECK(c.ring_key()[7] == 0.0F);
  CHECK(c.ring_key()[9] == Approx(1.0 / 60.0));
}

TEST_CASE("scan context sectors grow counter-clockwise from straight behind") {
  rgbl::ScanContextOptions options;
  options.rings = 2;
  options.sectors = 8;  // 45 deg each: sector 0 from -180 deg, sector 4 from 0 deg (ahead)
  options.min_range = 0.0;
  options.max_range = 20.0;  // rings of 10 m
  const double deg = std::numbers::pi / 180.0;
  const rgbl::ScanContext c = rgbl::make_scan_context(
      std::vector<rgbl::LidarPoint>{at(5.0, 10.0 * deg, 0.0), at(5.0, -10.0 * deg, 1.0), at(15.0, 100.0 * deg, 2.0),
                                    at(15.0, -170.0 * deg, 3.0)},
      options);
  CHECK(c.cell(0, 4) == Approx(2.0));  // ahead-left
  CHECK(c.cell(0, 3) == Approx(3.0));  // ahead-right
  CHECK(c.cell(1, 6) == Approx(4.0));  // left, slightly behind
  CHECK(c.cell(1, 0) == Approx(5.0));  // behind, right of straight back
  float total = 0.0F;
  for (int r = 0; r < 2; ++r) {
    for (int s = 0; s < 8; ++s) total += c.cell(r, s);
  }
  CHECK(total == Approx(14.0));  // no other cell holds anything
}

TEST_CASE("scan context finds the heading change of a rotated real scan") {
  if (!rgbl::test::kitti_seq04()) return;
  const auto scan = scan04(10);
  const rgbl::ScanContext original = rgbl::make_scan_context(scan);
  const double sector = 2.0 * std::numbers::pi / original.sectors();
  for (const int k : {7, -13, 30}) {
    // the sensor turned by k sectors: the scene turns by -k sectors in its frame
    const rgbl::ScanContext query = rgbl::make_scan_context(rotated(scan, -(k + 0.5) * sector));
    const rgbl::ScanContextMatch m = rgbl::compare(query, original);
    CAPTURE(k, m.distance, m.sector_shift, m.yaw);
    // half a sector off the grid, the worst case: every cell splits differently. Measured 0.175 for
    // each k (the descriptor's resolution; two scans 1.35 m apart give 0.13), yaw half a sector off.
    CHECK(m.distance < 0.25);
    CHECK(std::abs(std::remainder(m.yaw - (k + 0.5) * sector, 2.0 * std::numbers::pi)) < sector);
    // the coarse search lands on the best shift of all (measured: for every scan of 0..50 turned so)
    CHECK(rgbl::compare_all_shifts(query, original).distance == m.distance);
  }
  // An exact whole-sector rotation shifts whole columns: only a point within float rounding (~1e-7 rad)
  // of a sector edge could change cells. Measured: distance ~1e-17 for every k here and for frames 0..50
  // in steps of 5 turned by 1, 7, -13, 30, 59 sectors.
  for (const int k : {7, -13, 30}) {
    const rgbl::ScanContext query = rgbl::make_scan_context(rotated(scan, -k * sector));
    const rgbl::ScanContextMatch m = rgbl::compare(query, original);
    const rgbl::ScanContextMatch all = rgbl::compare_all_shifts(query, original);
    CAPTURE(k, m.distance, m.sector_shift, m.yaw);
    CHECK(m.distance < 1e-9);
    CHECK(m.sector_shift == (k + 60) % 60);
    CHECK(std::abs(std::remainder(m.yaw - k * sector, 2.0 * std::numbers::pi)) < 1e-12);
    CHECK(all.sector_shift == m.sector_shift);
    CHECK(all.distance == m.distance);
  }
  CHECK(rgbl::compare(original, original).distance == Approx(0.0).margin(1e-12));
  CHECK(rgbl::compare(original, original).sector_shift == 0);
}

TEST_CASE("scan context tells nearby places from distant ones on a real road") {
  if (!rgbl::test::kitti_seq04()) return;
  // sequence 04 drives ~1.35 m per frame on a straight rural road
  const rgbl::ScanContext f0 = rgbl::make_scan_context(scan04(0));
  const rgbl::ScanContext f1 = rgbl::make_scan_context(scan04(1));
  const rgbl::ScanContext f25 = rgbl::make_scan_context(scan04(25));
  const rgbl::ScanContext f50 = rgbl::make_scan_context(scan04(50));
  const double near = rgbl::compare(f1, f0).distance;
  const double mid = rgbl::compare(f25, f0).distance;
  const double far = rgbl::compare(f50, f0).distance;
  const double far_turned = rgbl::compare(rgbl::make_scan_context(rotated(scan04(50), 1.0)), f0).distance;
  CAPTURE(near, mid, far, far_turned);
  // measured: 1.35 m apart 0.130, 34 m apart 0.501, 69 m apart 0.625 (0.664 turned by 1 rad; 0.619 with
  // compare_all_shifts). Over frames 0..50: consecutive ones at most 0.204, >= 40 frames apart at least 0.568.
  CHECK(near < 0.3);
  CHECK(mid > 0.35);
  CHECK(far > 0.45);
  CHECK(far_turned > 0.45);
  CHECK(std::abs(rgbl::compare(f1, f0).yaw) <= 2.0 * std::numbers::pi / 60.0);  // driving straight: measured 0
  // the coarse search agrees with the full one on a true pair (measured: every pair <= 5 frames apart);
  // on distant pairs it may miss the best shift and score higher, never lower
  CHECK(rgbl::compare_all_shifts(f1, f0).distance == near);
  CHECK(rgbl::compare_all_shifts(f50, f0).distance <= far);
}

TEST_CASE("scan context's coarse shift search finds the full search's best shift for true pairs") {
  if (!rgbl::test::kitti_seq04()) return;
  std::vector<std::vector<rgbl::LidarPoint>> scans;
  std::vector<rgbl::ScanContext> contexts;
  for (int f = 0; f <= 20; ++f) {
    scans.push_back(scan04(f));
    contexts.push_back(rgbl::make_scan_context(scans.back()));
  }
  int compared = 0;
  for (int i = 0; i <= 20; ++i) {
    // each scan turned by its own off-grid angle, against itself and its neighbours up to 2 frames away
    const auto& scan = scans[static_cast<std::size_t>(i)];
    const rgbl::ScanContext query = rgbl::make_scan_context(rotated(scan, 0.37 * i + 0.05));
    for (int j = std::max(0, i - 2); j <= std::min(20, i + 2); ++j) {
      const rgbl::ScanContext& candidate = contexts[static_cast<std::size_t>(j)];
      const rgbl::ScanContextMatch coarse = rgbl::compare(query, candidate);
      const rgbl::ScanContextMatch all = rgbl::compare_all_shifts(query, candidate);
      CAPTURE(i, j, coarse.distance, all.distance, coarse.sector_shift, all.sector_shift);
      CHECK(coarse.distance == all.distance);
      CHECK(coarse.sector_shift == all.sector_shift);
      ++compared;
    }
  }
  CHECK(compared == 99);
}

TEST_CASE("scan context's coarse shift search over every pair of 51 real scans") {
  if (!rgbl::test::kitti_seq04()) return;
  std::vector<rgbl::ScanContext> contexts;
  for (int f = 0; f <= 50; ++f) contexts.push_back(rgbl::make_scan_context(scan04(f)));
  int near = 0, near_differ = 0, far = 0, far_differ = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < contexts.size(); ++i) {
    for (std::size_t j = 0; j < contexts.size(); ++j) {
      if (i == j) continue;
      const double coarse = rgbl::compare(contexts[i], contexts[j]).distance;
      const double all = rgbl::compare_all_shifts(contexts[i], contexts[j]).distance;
      CHECK(coarse >= all);  // a subset of the shifts: never better than the full search
      const bool differ = coarse != all;
      if (std::abs(static_cast<int>(i) - static_cast<int>(j)) <= 5) {
        ++near;
        near_differ += differ ? 1 : 0;
      } else {
        ++far;
        far_differ += differ ? 1 : 0;
        worst = std::max(worst, coarse - all);
      }
    }
  }
  // the figures in docs/loop-closing.md (measured: 0 of 480; 282 of 2070, worst +0.141)
  WARN("coarse vs full: " << near_differ << " of " << near << " pairs up to 5 frames apart differ; " << far_differ
                          << " of " << far << " farther pairs, worst +" << worst);
  CHECK(near_differ == 0);
  CHECK(far_differ < far / 4);
}

TEST_CASE("scan context database ranks the same place first and honours the filter") {
  if (!rgbl::test::kitti_seq04()) return;
  rgbl::ScanContextDatabase db;
  for (int f = 0; f <= 50; f += 5) db.add(static_cast<std::size_t>(f), rgbl::make_scan_context(scan04(f)));
  REQUIRE(db.size() == 11);
  const rgbl::ScanContext query = rgbl::make_scan_context(rotated(scan04(31), 0.8));  // near frame 30, turned
  const auto all = db.query(query, 11);
  REQUIRE(all.size() == 11);
  CHECK(all.front().id == 30);
  CHECK(std::abs(all.front().match.yaw + 0.8) < 2.0 * std::numbers::pi / 60.0);
  for (std::size_t i = 1; i < all.size(); ++i) CHECK(all[i - 1].match.distance <= all[i].match.distance);
  const auto filtered = db.query(query, 11, [](std::size_t id) { return id != 30; });
  REQUIRE(filtered.size() == 10);
  for (const auto& c : filtered) CHECK(c.id != 30);
}

TEST_CASE("scan context options are checked, naming the field") {
  const auto message_of = [](const rgbl::ScanContextOptions& o) -> std::string {
    try {
      o.validate();
    } catch (const rgbl::ConfigError& e) {
      return e.key() + " | " + e.what();
    }
    return "accepted";
  };
  CHECK(message_of({}) == "accepted");
  rgbl::ScanContextOptions o;
  o.rings = 0;
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.rings |"));
  o = {};
  o.sectors = 1;
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.sectors |"));
  o.sectors = 100000;  // rings x sectors would near int overflow
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.sectors |"));
  o = {};
  o.min_range = -1.0;
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.min_range |"));
  o.min_range = std::nan("");
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.min_range |"));
  o = {};
  o.max_range = std::numeric_limits<double>::infinity();
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.max_range |") && Catch::Contains("expected finite"));
  o = {};
  o.height_offset = std::nan("");
  CHECK_THAT(message_of(o), Catch::StartsWith("scan_context.height_offset |"));
  o = {};
  o.max_range = 1.0;  // below min_range; make_scan_context checks its options too
  CHECK_THROWS_WITH(rgbl::make_scan_context({}, o), Catch::Contains("scan_context.max_range"));
  rgbl::ScanContextOptions small;
  small.rings = 5;
  CHECK_THROWS_AS(rgbl::compare(rgbl::make_scan_context({}), rgbl::make_scan_context({}, small)), rgbl::ConfigError);
  CHECK_THROWS_AS(rgbl::compare_all_shifts(rgbl::make_scan_context({}), rgbl::make_scan_context({}, small)),
                  rgbl::ConfigError);
  // an empty scan matches nothing
  CHECK(rgbl::compare(rgbl::make_scan_context({}), rgbl::make_scan_context({})).distance == 1.0);
}
