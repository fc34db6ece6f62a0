#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/sim/synthetic.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstring>
#include <fstream>
#include <sstream>

using Catch::Matchers::WithinAbs;

namespace {

std::vector<std::string> lines(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

rgbl::Matrix34d parse_row(const std::string& line) {
  std::istringstream in(line);
  rgbl::Matrix34d M;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) in >> M(r, c);
  REQUIRE(in);
  return M;
}

}  // namespace

TEST_CASE("a written sequence has the KITTI odometry layout and reads back exactly") {
  rgbl::SyntheticOptions o;
  o.frames = 3;
  o.width = 200;
  o.height = 64;
  o.path.kind = rgbl::PathKind::curve;
  o.dropped_scans = {2};
  const rgbl::SyntheticSequence seq = rgbl::generate_sequence(o);
  const rgbl::test::TempDir dir;
  const rgbl::KittiLayout layout = rgbl::write_kitti(seq, dir.path(), 7);
  CHECK(layout.sequence_dir == dir.path() / "sequences" / "07");
  CHECK(layout.poses_file == dir.path() / "poses" / "07.txt");

  // calib.txt parses with the KITTI reader into the same rig
  const rgbl::KittiCalibration cal =
      rgbl::read_kitti_odometry_calibration(layout.sequence_dir / "calib.txt", o.width, o.height);
  for (std::size_t i = 0; i < 4; ++i) CHECK((cal.P[i] - seq.calibration.P[i]).norm() < 1e-9);
  CHECK((cal.T_cam0_lidar.matrix() - seq.calibration.T_cam0_lidar.matrix()).norm() < 1e-11);
  CHECK(cal.camera(2).camera.width == o.width);

  // poses: 12 numbers per line, first the identity
  const auto pose_lines = lines(layout.poses_file);
  REQUIRE(pose_lines.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    const Eigen::Isometry3d T = rgbl::isometry_from_3x4(parse_row(pose_lines[i]));
    CHECK((T.matrix() - seq.frames[i].T_world_cam0.matrix()).norm() < 1e-11);
  }
  CHECK(parse_row(pose_lines[0]) == rgbl::to_3x4(Eigen::Isometry3d::Identity()));
  CHECK(pose_lines[0].find("-0.") == std::string::npos);

  const auto times = lines(layout.sequence_dir / "times.txt");
  REQUIRE(times.size() == 3);
  CHECK_THAT(std::stod(times[2]), WithinAbs(0.2, 1e-9));

  for (int i = 0; i < 3; ++i) {
    const auto& f = seq.frames[static_cast<std::size_t>(i)];
    const std::string name = i == 0 ? "000000" : (i == 1 ? "000001" : "000002");
    for (int c = 0; c < 4; ++c) {
      const auto file = layout.sequence_dir / ("image_" + std::to_string(c)) / (name + ".png");
      const cv::Mat back = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
      REQUIRE(!back.empty());
      CHECK(back.type() == f.images[static_cast<std::size_t>(c)].type());
      CHECK(cv::norm(back, f.images[static_cast<std::size_t>(c)], cv::NORM_INF) == 0.0);
    }
    // velodyne: float32 x, y, z, reflectance, read by the KITTI reader
    const auto scan = rgbl::read_kitti_scan(layout.sequence_dir / "velodyne" / (name + ".bin"));
    REQUIRE(scan.size() == f.scan.size());
    CHECK((scan.empty() || std::memcmp(scan.data(), f.scan.data(), scan.size() * sizeof(rgbl::LidarPoint)) == 0));
    // depth: uint16 PNG, depth * 256
    const cv::Mat depth = cv::imread((layout.sequence_dir / "depth" / (name + ".png")).string(), cv::IMREAD_UNCHANGED);
    REQUIRE(depth.type() == CV_16UC1);
    int compared = 0;
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        const float exact = f.depth(v, u);
        const double stored = depth.at<std::uint16_t>(v, u) / 256.0;
        if (exact == 0.0F || exact * 256.0F > 65535.0F) {
          REQUIRE(stored == 0.0);
        } else {
          REQUIRE(std::abs(stored - exact) <= 0.5 / 256.0 + 1e-6);
          ++compared;
        }
      }
    }
    CHECK(compared > depth.rows * depth.cols / 2);
  }
  CHECK(seq.frames[2].scan.empty());  // a dropped scan is an empty file
  CHECK(std::filesystem::file_size(layout.sequence_dir / "velodyne" / "000002.bin") == 0);
  CHECK(std::filesystem::exists(layout.sequence_dir / "sim.txt"));
}

TEST_CASE("streaming writer: same files as the in-memory sequence") {
  rgbl::SyntheticOptions o;
  o.frames = 2;
  o.width = 120;
  o.height = 40;
  const rgbl::test::TempDir dir;
  int reported = 0;
  const rgbl::SyntheticGenerator g(o);
  const auto a = rgbl::write_kitti(g, dir.path() / "a", 0, [&](int) { ++reported; });
  const auto b = rgbl::write_kitti(rgbl::generate_sequence(o), dir.path() / "b", 0);
  CHECK(reported == 2);
  for (const char* rel : {"image_0/000001.png", "image_3/000001.png", "velodyne/000001.bin", "depth/000001.png",
                          "calib.txt", "times.txt"}) {
    std::ifstream fa(a.sequence_dir / rel, std::ios::binary), fb(b.sequence_dir / rel, std::ios::binary);
    const std::string sa((std::istreambuf_iterator<char>(fa)), {}), sb((std::istreambuf_iterator<char>(fb)), {});
    INFO(rel);
    CHECK(!sa.empty());
    CHECK(sa == sb);
  }
}
