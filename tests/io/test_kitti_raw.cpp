#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/io/kitti_raw.hpp"
#include "rgbl/io/sequence.hpp"
#include "support/data.hpp"
#include "support/temp_dir.hpp"
#include "support/parse_error.hpp"

#include "synthetic.hpp"

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <numbers>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

TEST_CASE("OXTS packets to metric IMU poses (devkit Mercator)", "[io][kitti-raw]") {
  rgbl::OxtsPacket a;
  a.lat = 49.0;
  a.lon = 8.4;
  a.alt = 100.0;
  a.yaw = 0.3;
  rgbl::OxtsPacket b = a;
  b.lon += 1e-4;  // east
  b.alt += 2.0;   // up
  rgbl::OxtsPacket c = a;
  c.yaw += 0.5;  // turn left in place
  c.roll = 0.1;
  const std::vector<rgbl::OxtsPacket> packets{a, b, c};
  const auto poses = rgbl::oxts_imu_poses(packets);
  REQUIRE(poses.size() == 3);
  CHECK(poses[0].isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  // east by cos(lat) * dlon * R; expressed in the first IMU frame, which is yawed by 0.3 rad
  const double east = std::cos(49.0 * std::numbers::pi / 180.0) * 1e-4 * std::numbers::pi / 180.0 * 6378137.0;
  const Eigen::Vector3d t = poses[1].translation();
  CHECK_THAT(t.norm(), WithinRel(std::hypot(east, 2.0), 1e-9));
  CHECK_THAT(t.x(), WithinAbs(east * std::cos(0.3), 1e-6));
  CHECK_THAT(t.y(), WithinAbs(-east * std::sin(0.3), 1e-6));
  CHECK_THAT(t.z(), WithinAbs(2.0, 1e-9));
  // rotation relative to the first: yaw 0.5 then roll 0.1 (R = Rz Ry Rx)
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                                   Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()).toRotationMatrix();
  CHECK((poses[2].linear() - expected).norm() < 1e-12);
  CHECK(poses[2].translation().norm() < 1e-9);
}

TEST_CASE("KITTI raw drive: frames, calibration and OXTS ground truth", "[io][kitti-raw][data]") {
  const auto dir = rgbl::test::find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync");
  if (!dir) return;
  const auto seq = rgbl::open_sequence(*dir);
  CHECK(seq->format() == rgbl::DatasetFormat::kitti_raw);
  REQUIRE(seq->size() == 10);
  CHECK(seq->sensors().cameras == std::array<bool, 4>{true, true, true, false});
  CHECK(seq->sensors().lidar);
  CHECK(seq->calibration().width[0] == 1242);
  CHECK(seq->calibration().height[2] == 375);
  // 2011-09-26 13:08:24.973999360, then ~0.1035 s steps
  CHECK_THAT(seq->timestamp(0), WithinAbs(1317042504.973999360, 1e-5));
  CHECK_THAT(seq->timestamp(1) - seq->timestamp(0), WithinAbs(0.1038008, 1e-5));

  REQUIRE(seq->ground_truth());
  const auto& gt = seq->ground_truth()->poses;
  REQUIRE(gt.size() == 10);
  CHECK(gt[0].isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  // Consecutive cam0 displacements agree with the OXTS ground speed (vf, vl) times the camera's dt (the
  // packets, up to 10 ms off the camera times, are interpolated to them; GPS and velocity agree to
  // ~1%), and the car drives along cam0's +z.
  const auto oxts = *dir / "oxts" / "data";
  std::vector<double> oxts_seconds;  // all within 13:08
  {
    std::ifstream in(*dir / "oxts" / "timestamps.txt");
    for (std::string line; std::getline(in, line);) oxts_seconds.push_back(std::stod(line.substr(17)));
  }
  REQUIRE(oxts_seconds.size() == 10);
  for (std::size_t i = 0; i + 1 < 10; ++i) {
    const auto p0 = rgbl::read_oxts_packet(oxts / fmt::format("{:010}.txt", i));
    const auto p1 = rgbl::read_oxts_packet(oxts / fmt::format("{:010}.txt", i + 1));
    const double speed = 0.5 * (std::hypot(p0.vf, p0.vl) + std::hypot(p1.vf, p1.vl));
    const double dt = seq->timestamp(i + 1) - seq->timestamp(i);
    const Eigen::Vector3d step = gt[i].inverse() * gt[i + 1].translation();
    INFO("frame " << i << " step " << step.transpose() << " speed*dt " << speed * dt);
    CHECK_THAT(step.norm(), WithinRel(speed * dt, 0.02));
    CHECK(step.z() > 0.95 * step.norm());
  }
  const auto f = seq->load(9);
  CHECK(f.grey_left().cols == 1242);
  CHECK(f.colour_left().type() == CV_8UC3);
  CHECK(f.scan.size() > 100000);
  REQUIRE(f.T_world_cam0);
  CHECK(f.T_world_cam0->matrix() == gt[9].matrix());
}

TEST_CASE("KITTI raw loader: bad input names the file", "[io][kitti-raw][bad-input]") {
  rgbl::test::TempDir tmp;
  const auto drive = tmp.path() / "2011_01_01_drive_0001_sync";
  const auto oxts = tmp.write("2011_01_01_drive_0001_sync/oxts/data/0000000000.txt", "49.0 8.4 100 0 0 zero\n");
  CHECK_THROWS_WITH(rgbl::read_oxts_packet(oxts), Contains(oxts.string()) && Contains("expected 30 numbers"));
  std::string packet = "49.0 8.4 100 0 0 0.1";
  for (int k = 6; k < 30; ++k) packet += k == 8 ? " fast" : " 0";
  tmp.write("2011_01_01_drive_0001_sync/oxts/data/0000000000.txt", packet);
  CHECK_THROWS_WITH(rgbl::read_oxts_packet(oxts), Contains("field 9 'fast' is not a finite number"));
  const auto calib = tmp.write("calib_imu_to_velo.txt", "R: 1 0 0 0 1 0 0 0 1\n");
  CHECK_THROWS_WITH(rgbl::read_kitti_rigid_transform(calib), Contains(calib.string()) && Contains("'T: '"));
  // no calibration files one level up
  std::filesystem::create_directories(drive / "velodyne_points" / "data");
  CHECK_THROWS_WITH(rgbl::open_kitti_raw(drive), Contains("calib_cam_to_cam.txt"));
}

namespace {

// A date folder with a 3-frame drive of 8x6 grey images, scans and OXTS packets.
struct SyntheticRaw {
  rgbl::test::TempDir tmp;
  std::filesystem::path drive;

  SyntheticRaw() {
    drive = tmp.path() / "2011_01_01_drive_0001_sync";
    std::string cam;
    for (int i = 0; i < 4; ++i) {
      cam += fmt::format("S_rect_0{}: 8 6\nP_rect_0{}: 50 0 3.5 0 0 50 2.5 0 0 0 1 0\n", i, i);
    }
    cam += "R_rect_00: 1 0 0 0 1 0 0 0 1\n";
    tmp.write("calib_cam_to_cam.txt", cam);
    tmp.write("calib_velo_to_cam.txt", "R: 0 -1 0 0 0 -1 1 0 0\nT: 0 -0.08 -0.27\n");
    tmp.write("calib_imu_to_velo.txt", "R: 1 0 0 0 1 0 0 0 1\nT: -0.8 0.3 -0.8\n");
    std::string times;
    for (int i = 0; i < 3; ++i) {
      times += fmt::format("2011-01-01 10:00:0{}.500000000\n", i);
      rgbl::test::write_png(drive / "image_00" / "data" / fmt::format("{:010}.png", i), 8, 6, 1, i);
      rgbl::test::write_bin(drive / "velodyne_points" / "data" / fmt::format("{:010}.bin", i), {5, 0, 0, 1});
      std::string packet = fmt::format("49.0 {} 100 0 0 0", 8.4 + 1e-5 * i);
      for (int k = 6; k < 30; ++k) packet += " 0";
      tmp.write(fmt::format("2011_01_01_drive_0001_sync/oxts/data/{:010}.txt", i), packet + "\n");
    }
    tmp.write("2011_01_01_drive_0001_sync/image_00/timestamps.txt", times);
  }
  std::filesystem::path oxts(int i) const { return drive / "oxts" / "data" / fmt::format("{:010}.txt", i); }
};

}  // namespace

TEST_CASE("synthetic KITTI raw drive", "[io][kitti-raw]") {
  SyntheticRaw raw;
  const auto seq = rgbl::open_kitti_raw(raw.drive);
  REQUIRE(seq->size() == 3);
  CHECK(seq->sensors().cameras == std::array<bool, 4>{true, false, false, false});
  CHECK_THAT(seq->timestamp(2) - seq->timestamp(0), WithinAbs(2.0, 1e-6));
  CHECK_THAT(seq->timestamp(0), WithinAbs(1293876000.5, 1e-6));  // 2011-01-01 10:00:00.5 UTC
  // heading east (yaw 0) = IMU x = LiDAR x = cam0 z: 1e-5 deg of longitude per frame
  const double step = std::cos(49.0 * std::numbers::pi / 180.0) * 1e-5 * std::numbers::pi / 180.0 * 6378137.0;
  const auto& gt = seq->ground_truth()->poses;
  CHECK_THAT(gt[2].translation().z(), WithinAbs(2 * step, 1e-6));
  CHECK_THAT(gt[2].translation().x(), WithinAbs(0.0, 1e-6));
  CHECK(gt[2].linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));

  // With the OXTS unit's own timestamps (packets at 0.0, 1.0, 2.5 s; frames at 0.5, 1.5, 2.5 s) the
  // poses are interpolated to the frames' times: 0.5, 1 + 1/3 and 2 packet steps, re-anchored at the
  // first frame.
  raw.tmp.write("2011_01_01_drive_0001_sync/oxts/timestamps.txt",
                "2011-01-01 10:00:00.000000000\n2011-01-01 10:00:01.000000000\n2011-01-01 10:00:02.500000000\n");
  const auto timed = rgbl::open_kitti_raw(raw.drive);
  const auto& gt_timed = timed->ground_truth()->poses;
  CHECK(gt_timed[0].isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  CHECK_THAT(gt_timed[1].translation().z(), WithinAbs((4.0 / 3.0 - 0.5) * step, 1e-6));
  CHECK_THAT(gt_timed[2].translation().z(), WithinAbs(1.5 * step, 1e-6));
  CHECK_THAT(gt_timed[2].translation().x(), WithinAbs(0.0, 1e-6));

  // timestamps that do not increase cannot be interpolated: packet by packet, with a note
  raw.tmp.write("2011_01_01_drive_0001_sync/oxts/timestamps.txt",
                "2011-01-01 10:00:00.000000000\n2011-01-01 10:00:01.000000000\n2011-01-01 10:00:01.000000000\n");
  const auto untimed = rgbl::open_kitti_raw(raw.drive);
  CHECK_THAT(untimed->ground_truth()->poses[2].translation().z(), WithinAbs(2 * step, 1e-6));
}

TEST_CASE("KITTI raw loader: missing packets, counts and sizes", "[io][kitti-raw][bad-input]") {
  SECTION("an OXTS packet missing in the middle") {
    SyntheticRaw raw;
    std::filesystem::remove(raw.oxts(1));
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive), Contains(raw.oxts(1).string()) && Contains("missing"));
  }
  SECTION("fewer OXTS packets than frames") {
    SyntheticRaw raw;
    std::filesystem::remove(raw.oxts(2));
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive), Contains(raw.oxts(2).string()));
  }
  SECTION("timestamps count differs") {
    SyntheticRaw raw;
    const auto file = raw.tmp.write("2011_01_01_drive_0001_sync/image_00/timestamps.txt", "2011-01-01 10:00:00.5\n");
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive),
                      Contains(file.string()) && Contains("has 1 timestamps, expected 3"));
  }
  SECTION("malformed timestamp") {
    SyntheticRaw raw;
    const auto file = raw.tmp.write("2011_01_01_drive_0001_sync/image_00/timestamps.txt",
                                    "2011-01-01 10:00:00.5\n2011-01-01 10:0x:01.5\n2011-01-01 10:00:02.5\n");
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive), Contains(file.string() + ":2:"));
  }
  SECTION("first image does not match the calibration's S_rect") {
    SyntheticRaw raw;
    const auto image = raw.drive / "image_00" / "data" / "0000000000.png";
    rgbl::test::write_png(image, 10, 6, 1, 0);
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive), Contains(image.string()) && Contains("calibration says 8x6"));
  }
  SECTION("without calib_imu_to_velo.txt: no ground truth, and a note says why") {
    SyntheticRaw raw;
    std::filesystem::remove(raw.tmp.path() / "calib_imu_to_velo.txt");
    const auto seq = rgbl::open_kitti_raw(raw.drive);
    CHECK_FALSE(seq->ground_truth());
    CHECK_THAT(seq->notes().at(0), Contains("calib_imu_to_velo.txt is missing"));
  }
}

TEST_CASE("KITTI raw loader: frame timestamps must increase strictly", "[io][kitti-raw][bad-input]") {
  SyntheticRaw raw;
  const auto times = raw.drive / "image_00" / "timestamps.txt";
  raw.tmp.write("2011_01_01_drive_0001_sync/image_00/timestamps.txt",
                "2011-01-01 10:00:00.500000000\n2011-01-01 10:00:01.500000000\n2011-01-01 10:00:01.500000000\n");
  CHECK_THAT(rgbl::test::parse_error_message([&] { rgbl::open_kitti_raw(raw.drive); }, times),
             Contains(":3: timestamp") && Contains("is not after the one on line 2"));
  raw.tmp.write("2011_01_01_drive_0001_sync/image_00/timestamps.txt",
                "2011-01-01 10:00:02.500000000\n2011-01-01 10:00:01.500000000\n2011-01-01 10:00:03.500000000\n");
  CHECK_THAT(rgbl::test::parse_error_message([&] { rgbl::read_kitti_raw_timestamps(times); }, times),
             Contains(":2: timestamp"));
}

TEST_CASE("KITTI raw loader: each scan's forward-facing time from velodyne_points/timestamps.txt", "[io][kitti-raw]") {
  SyntheticRaw raw;
  CHECK_FALSE(rgbl::open_kitti_raw(raw.drive)->load(1).scan_timestamp);  // no file: the dataset does not say
  raw.tmp.write("2011_01_01_drive_0001_sync/velodyne_points/timestamps.txt",
                "2011-01-01 10:00:00.480000000\n2011-01-01 10:00:01.483000000\n2011-01-01 10:00:02.490000000\n");
  const auto seq = rgbl::open_kitti_raw(raw.drive);
  for (std::size_t i = 0; i < 3; ++i) {
    const rgbl::FrameInput frame = seq->load(i);
    REQUIRE(frame.scan_timestamp);
    CHECK_THAT(frame.timestamp - *frame.scan_timestamp, WithinAbs(std::array{0.020, 0.017, 0.010}[i], 1e-6));
  }
  SECTION("a count that differs names the file") {
    const auto file = raw.tmp.write("2011_01_01_drive_0001_sync/velodyne_points/timestamps.txt",
                                    "2011-01-01 10:00:00.480000000\n");
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive), Contains(file.string()) && Contains("has 1 timestamps, expected 3"));
  }
  SECTION("a scan more than a second from its image is a glitch: that frame has no scan time, and a note says so") {
    const auto file = raw.tmp.write("2011_01_01_drive_0001_sync/velodyne_points/timestamps.txt",
                                    "2011-01-01 10:00:00.480000000\n2011-01-01 10:00:03.483000000\n"
                                    "2011-01-01 10:00:02.490000000\n");
    const auto glitch = rgbl::open_kitti_raw(raw.drive);
    CHECK(glitch->load(0).scan_timestamp);
    CHECK_FALSE(glitch->load(1).scan_timestamp);
    CHECK(glitch->load(2).scan_timestamp);
    REQUIRE(glitch->notes().size() == 1);
    CHECK_THAT(glitch->notes()[0], Contains(file.string()) && Contains("1 scan time(s) more than 1 s") &&
                                       Contains("first at frame 1 (-1.983 s)"));
  }
  SECTION("a malformed scan time names the file and line") {
    const auto file = raw.tmp.write("2011_01_01_drive_0001_sync/velodyne_points/timestamps.txt",
                                    "2011-01-01 10:00:00.480000000\nnot a time\n2011-01-01 10:00:02.490000000\n");
    CHECK_THROWS_WITH(rgbl::open_kitti_raw(raw.drive), Contains(file.string() + ":2:"));
  }
}

TEST_CASE("KITTI raw drive: the cameras' timestamps come 16.6-17.1 ms after the scan faced forward",
          "[io][kitti-raw][data]") {
  const auto dir = rgbl::test::find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync");
  if (!dir) return;
  const auto seq = rgbl::open_sequence(*dir);
  for (std::size_t i = 0; i < seq->size(); ++i) {
    const rgbl::FrameInput frame = seq->load(i);
    REQUIRE(frame.scan_timestamp);
    const double age = frame.timestamp - *frame.scan_timestamp;
    CHECK(age > 0.0166);
    CHECK(age < 0.0171);
  }
}
