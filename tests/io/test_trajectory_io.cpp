#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/io/trajectory_io.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

using Catch::Matchers::Contains;

namespace {

std::vector<Eigen::Isometry3d> wiggly_poses(std::size_t n) {
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i);
    rgbl::Vector6d xi;
    xi << 0.3 * s + 1.0 / 3.0, -0.1 * s, 1.7 * s + 1e-9, 0.01 * s, std::sqrt(2.0) * 0.1 * s, -0.02 * s;
    poses.push_back(rgbl::se3_exp(xi));
  }
  return poses;
}

template <typename F>
void require_parse_error(F&& f, const std::filesystem::path& file, std::size_t line, const std::string& text) {
  try {
    f();
    FAIL("no ParseError");
  } catch (const rgbl::ParseError& e) {
    CHECK(e.file() == file);
    CHECK(e.line() == line);
    CHECK_THAT(e.what(), Contains(file.string()) && Contains(text));
  }
}

}  // namespace

TEST_CASE("KITTI trajectory round trip is exact", "[io][trajectory]") {
  rgbl::test::TempDir tmp;
  const auto poses = wiggly_poses(20);
  const auto file = tmp.path() / "traj.txt";
  rgbl::write_kitti_trajectory(file, poses);
  CHECK_FALSE(std::filesystem::exists(tmp.path() / "traj.txt.part"));
  const auto back = rgbl::read_kitti_trajectory(file);
  REQUIRE(back.size() == poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) CHECK(back[i].matrix() == poses[i].matrix());
  // one row-major 3x4 per line: the first line of the identity-free pose 0 is R row 0 then t.x
  std::istringstream first_line(rgbl::test::read_file(file));
  std::vector<double> v(12);
  for (auto& x : v) first_line >> x;
  CHECK(v[3] == poses[0].translation().x());
  CHECK(v[4] == poses[0].linear()(1, 0));
}

TEST_CASE("TUM trajectory round trip keeps timestamps and poses", "[io][trajectory]") {
  rgbl::test::TempDir tmp;
  rgbl::Trajectory t;
  t.poses = wiggly_poses(15);
  for (std::size_t i = 0; i < t.poses.size(); ++i)
    t.timestamps.push_back(1305031102.175304 + 0.0333 * static_cast<double>(i));
  const auto file = tmp.path() / "traj_tum.txt";
  rgbl::write_tum_trajectory(file, t);
  const auto back = rgbl::read_tum_trajectory(file);
  REQUIRE(back.size() == t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    CHECK(back.timestamps[i] == t.timestamps[i]);
    CHECK(back.poses[i].translation() == t.poses[i].translation());
    // the quaternion passes through 17 significant digits: rotation equal to ~1e-15
    CHECK((back.poses[i].linear() - t.poses[i].linear()).cwiseAbs().maxCoeff() < 1e-14);
  }
  // format: t tx ty tz qx qy qz qw
  rgbl::test::TempDir tmp2;
  const auto one = tmp2.write("one.txt", "# comment\n\n10.5 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n");
  const auto tr = rgbl::read_tum_trajectory(one);
  REQUIRE(tr.size() == 1);
  CHECK(tr.timestamps[0] == 10.5);
  CHECK(tr.poses[0].translation() == Eigen::Vector3d(1, 2, 3));
  CHECK(std::abs(rgbl::rotation_angle(tr.poses[0].linear()) - std::numbers::pi / 2) < 1e-12);
  CHECK(std::abs((tr.poses[0].linear() * Eigen::Vector3d::UnitX()).y() - 1.0) < 1e-12);  // +90 deg about z
}

TEST_CASE("trajectory readers name file and line of malformed rows", "[io][trajectory][bad-input]") {
  rgbl::test::TempDir tmp;
  const auto short_row = tmp.write("a.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  require_parse_error([&] { rgbl::read_kitti_trajectory(short_row); }, short_row, 2, "expected 12 numbers");
  const auto text = tmp.write("b.txt", "1 0 0 0 0 1 0 0 0 0 1 abc\n");
  require_parse_error([&] { rgbl::read_kitti_trajectory(text); }, text, 1, "'abc' is not a finite number");
  const auto nan = tmp.write("c.txt", "\n\n1 0 0 0 0 1 0 0 0 0 1 nan\n");
  require_parse_error([&] { rgbl::read_kitti_trajectory(nan); }, nan, 3, "not a finite number");
  const auto not_rotation = tmp.write("d.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n");
  require_parse_error([&] { rgbl::read_kitti_trajectory(not_rotation); }, not_rotation, 1, "not a rotation");
  const auto tum_short = tmp.write("e.txt", "1 2 3 4 0 0 0 1\n2 2 3 4 0 0 0\n");
  require_parse_error([&] { rgbl::read_tum_trajectory(tum_short); }, tum_short, 2, "expected 8 numbers");
  const auto tum_quat = tmp.write("f.txt", "1 2 3 4 0 0 0 0\n");
  require_parse_error([&] { rgbl::read_tum_trajectory(tum_quat); }, tum_quat, 1, "quaternion norm");
  const auto tum_order = tmp.write("g.txt", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n");
  require_parse_error([&] { rgbl::read_tum_trajectory(tum_order); }, tum_order, 2, "timestamps must increase");
  // a KITTI file read as TUM: 12 fields
  const auto kitti_as_tum = tmp.write("h.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  require_parse_error([&] { rgbl::read_tum_trajectory(kitti_as_tum); }, kitti_as_tum, 1, "found 12 fields");
  const auto missing = tmp.path() / "nope.txt";
  require_parse_error([&] { rgbl::read_kitti_trajectory(missing); }, missing, 0, "missing (expected a KITTI trajectory");
  require_parse_error([&] { rgbl::read_tum_trajectory(tmp.path()); }, tmp.path(), 0, "is a directory");
}

TEST_CASE("writers fail with the file name and leave nothing that looks complete", "[io][trajectory][bad-input]") {
  rgbl::test::TempDir tmp;
  const auto file = tmp.path() / "no_such_dir" / "traj.txt";
  const auto poses = wiggly_poses(2);
  CHECK_THROWS_WITH(rgbl::write_kitti_trajectory(file, poses), Contains(file.string()));
  CHECK_FALSE(std::filesystem::exists(file));
  rgbl::Trajectory t;
  t.poses = poses;
  t.timestamps = {1.0};
  CHECK_THROWS_WITH(rgbl::write_tum_trajectory(tmp.path() / "x.txt", t), Contains("1 timestamps for 2 poses"));
}

TEST_CASE("timestamp association pairs nearest stamps greedily", "[io][trajectory]") {
  const std::vector<double> a{0.0, 0.03, 0.1, 0.2};
  const std::vector<double> b{0.016, 0.031, 0.5};
  const auto pairs = rgbl::associate_timestamps(a, b, 0.02);
  // (0.03, 0.031) is the closest pair; 0.0 then takes 0.016; 0.1 and 0.2 have nothing within 0.02
  REQUIRE(pairs.size() == 2);
  CHECK(pairs[0] == std::pair<std::size_t, std::size_t>{0, 0});
  CHECK(pairs[1] == std::pair<std::size_t, std::size_t>{1, 1});
  CHECK(rgbl::associate_timestamps(a, {}, 0.02).empty());
}
