#include "rgbl/core/error.hpp"
#include "rgbl/io/ply.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using Catch::Matchers::Contains;

TEST_CASE("PLY: coloured points and camera pyramids", "[io][ply]") {
  rgbl::test::TempDir tmp;
  const std::vector<Eigen::Vector3d> points{{1, 2, 3}, {-0.5, 0.25, 10}};
  const std::vector<std::array<std::uint8_t, 3>> colours{{{255, 0, 0}}, {{1, 2, 3}}};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0, 0, 5);
  const std::vector<Eigen::Isometry3d> cams{Eigen::Isometry3d::Identity(), T};
  const auto file = tmp.path() / "map.ply";
  rgbl::write_ply(file, points, colours, cams, {1.0, {{0, 255, 0}}, {{9, 9, 9}}});

  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  const auto header_end = std::find(lines.begin(), lines.end(), "end_header");
  REQUIRE(header_end != lines.end());
  CHECK(lines[0] == "ply");
  CHECK(std::find(lines.begin(), header_end, "element vertex 12") != header_end);  // 2 + 2 * 5
  CHECK(std::find(lines.begin(), header_end, "element face 8") != header_end);
  const auto body = static_cast<std::size_t>(header_end - lines.begin()) + 1;
  REQUIRE(lines.size() == body + 12 + 8);
  CHECK(lines[body] == "1 2 3 255 0 0");
  CHECK(lines[body + 1] == "-0.5 0.25 10 1 2 3");
  CHECK(lines[body + 2] == "0 0 0 0 255 0");                       // apex of camera 0
  CHECK(lines[body + 7] == "0 0 5 0 255 0");                       // apex of camera 1
  CHECK(lines[body + 8] == "-0.5 -0.3333333333333333 6 0 255 0");  // a base corner 1 m ahead
  CHECK(lines[body + 12] == "3 2 3 4");
  CHECK(lines[body + 19] == "3 7 11 8");
}

TEST_CASE("PLY: bad arguments name the problem", "[io][ply][bad-input]") {
  rgbl::test::TempDir tmp;
  const std::vector<Eigen::Vector3d> points{{1, 2, 3}};
  const std::vector<std::array<std::uint8_t, 3>> two{{{1, 1, 1}}, {{2, 2, 2}}};
  CHECK_THROWS_WITH(rgbl::write_ply(tmp.path() / "a.ply", points, two, {}), Contains("2 colours for 1 points"));
  CHECK_THROWS_WITH(rgbl::write_ply(tmp.path() / "no" / "a.ply", points, {}, {}), Contains("cannot open for writing"));
  CHECK_THROWS_AS(rgbl::write_ply(tmp.path() / "b.ply", points, {}, {}, {0.0}), rgbl::ConfigError);
}
