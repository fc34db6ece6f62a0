#include "rgbl/place/scan_context.hpp"

#include "rgbl/core/error.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>

#include <cmath>
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
  const double sector = 2.0 * M_PI / options.sectors;
  std::vector<rgbl::LidarPoint> scan{
      at(10.0, -M_PI + 0.5 * sector, -1.7),   // road: ring 2, sector 0
      at(10.5, -M_PI + 0.4 * sector, 1.3),    // a pole in the same cell: its top wins
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

TEST_CASE("scan context finds the heading change of a rotated real scan") {
  if (!rgbl::test::kitti_seq04()) return;
  const auto scan = scan04(10);
  const rgbl::ScanContext original = rgbl::make_scan_context(scan);
  const double sector = 2.0 * M_PI / original.sectors();
  for (const int k : {7, -13, 30}) {
    // the sensor turned by k sectors: the scene turns by -k sectors in its frame
    const rgbl::ScanContext query = rgbl::make_scan_context(rotated(scan, -(k + 0.5) * sector));
    const rgbl::ScanContextMatch m = rgbl::compare(query, original);
    CAPTURE(k, m.distance, m.sector_shift, m.yaw);
    // half a sector off the grid, the worst case: every cell splits differently. Measured 0.175 for
    // each k (the descriptor's resolution; two scans 1.35 m apart give 0.13), yaw half a sector off.
    CHECK(m.distance < 0.25);
    CHECK(std::abs(std::remainder(m.yaw - (k + 0.5) * sector, 2.0 * M_PI)) < sector);
  }
  // an exact whole-sector rotation shifts whole columns: only points on a sector edge can move cells
  const rgbl::ScanContext query = rgbl::make_scan_context(rotated(scan, -7.0 * sector));
  const rgbl::ScanContextMatch m = rgbl::compare(query, original);
  CHECK(m.sector_shift == 7);
  CHECK(m.yaw == Approx(7.0 * sector));
  CHECK(m.distance < 1e-3);
  CHECK(rgbl::compare(original, original).distance == Approx(0.0).margin(1e-12));
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
  // measured: 1.35 m apart 0.13, 34 m apart 0.50, 69 m apart 0.62 (0.62 turned by 1 rad)
  CHECK(near < 0.3);
  CHECK(mid > 0.35);
  CHECK(far > 0.45);
  CHECK(far_turned > 0.45);
  CHECK(std::abs(rgbl::compare(f1, f0).sector_shift) <= 1);
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
  CHECK(std::abs(all.front().match.yaw + 0.8) < 2.0 * M_PI / 60.0);
  for (std::size_t i = 1; i < all.size(); ++i) CHECK(all[i - 1].match.distance <= all[i].match.distance);
  const auto filtered = db.query(query, 11, [](std::size_t id) { return id != 30; });
  REQUIRE(filtered.size() == 10);
  for (const auto& c : filtered) CHECK(c.id != 30);
}

TEST_CASE("scan context options are checked, naming the field") {
  rgbl::ScanContextOptions o;
  o.sectors = 1;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("scan_context.sectors"));
  o = {};
  o.max_range = 1.0;
  CHECK_THROWS_WITH(rgbl::make_scan_context({}, o), Catch::Contains("scan_context.max_range"));
  rgbl::ScanContextOptions small;
  small.rings = 5;
  CHECK_THROWS_AS(rgbl::compare(rgbl::make_scan_context({}), rgbl::make_scan_context({}, small)), rgbl::ConfigError);
  // an empty scan matches nothing
  CHECK(rgbl::compare(rgbl::make_scan_context({}), rgbl::make_scan_context({})).distance == 1.0);
}
