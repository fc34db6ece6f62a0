#include "rgbl/core/error.hpp"
#include "rgbl/io/sequence.hpp"
#include "support/data.hpp"
#include "support/parse_error.hpp"
#include "synthetic.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <filesystem>
#include <limits>
#include <vector>
#include <sys/stat.h>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

using rgbl::test::parse_error_message;

}  // namespace

TEST_CASE("KITTI odometry sequence 04 as the loader sees it", "[io][kitti][data]") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  const auto seq = rgbl::open_sequence(*dir);
  CHECK(seq->format() == rgbl::DatasetFormat::kitti);
  CHECK(seq->name() == "04");
  REQUIRE(seq->size() == 51);
  CHECK(seq->sensors().cameras == std::array<bool, 4>{true, true, true, false});
  CHECK(seq->sensors().lidar);
  const auto& calib = seq->calibration();
  CHECK(calib.width[0] == 1226);
  CHECK(calib.height[2] == 370);
  CHECK(calib.width[3] == 0);
  CHECK(calib.P[2](0, 3) == 46.88783);
  CHECK(seq->timestamp(0) == 0.0);
  CHECK_THAT(seq->timestamp(50), WithinAbs(5.16, 0.2));
  // poses/04.txt has 271 rows: the first 51 are used, and the loader says so
  REQUIRE(seq->ground_truth());
  CHECK(seq->ground_truth()->size() == 51);
  REQUIRE(seq->notes().size() == 1);
  CHECK_THAT(seq->notes()[0], Contains("first 51 of the 271 poses"));
  CHECK(seq->ground_truth()->poses[0].isApprox(Eigen::Isometry3d::Identity(), 1e-5));

  const rgbl::FrameInput f = seq->load(50);
  CHECK(f.index == 50);
  CHECK(f.grey_left().type() == CV_8UC1);
  CHECK(f.grey_left().cols == 1226);
  CHECK(f.grey_right().rows == 370);
  CHECK(f.colour_left().type() == CV_8UC3);
  CHECK(f.colour_right().empty());
  CHECK(f.scan.size() > 100000);
  CHECK(f.scan.size() < 140000);
  REQUIRE(f.T_world_cam0);
  CHECK(f.T_world_cam0->matrix() == seq->ground_truth()->poses[50].matrix());
  // sequence 04 drives ~69 m straight ahead (+z in cam0)
  CHECK_THAT(f.T_world_cam0->translation().z(), WithinAbs(69.0, 5.0));

  rgbl::LoadOptions only_lidar;
  only_lidar.cameras = {false, false, false, false};
  const auto lidar_seq = rgbl::open_kitti_odometry(*dir, only_lidar);
  const auto g = lidar_seq->load(0);
  CHECK(g.grey_left().empty());
  CHECK_FALSE(g.scan.empty());
  rgbl::LoadOptions only_right;
  only_right.cameras = {false, true, false, false};
  only_right.lidar = false;
  const auto h = seq->load(1, only_right);
  CHECK(h.grey_left().empty());
  CHECK(h.grey_right().cols == 1226);
  CHECK(h.scan.empty());
}

TEST_CASE("synthetic KITTI sequence loads every sensor", "[io][kitti]") {
  rgbl::test::SyntheticKitti kitti(3, 5);
  const auto seq = rgbl::open_kitti_odometry(kitti.dir / "");  // a trailing slash is fine
  CHECK(seq->name() == "07");
  REQUIRE(seq->size() == 3);
  CHECK(seq->sensors().cameras == std::array<bool, 4>{true, false, true, false});
  CHECK(seq->calibration().width[2] == 8);
  CHECK(seq->calibration().height[0] == 6);
  CHECK(seq->ground_truth()->size() == 3);
  CHECK_THAT(seq->notes().at(0), Contains("first 3 of the 5 poses"));
  const auto f = seq->load(2);
  CHECK(f.timestamp == 0.2);
  CHECK(f.grey_left().at<std::uint8_t>(0, 0) == 12);
  CHECK(f.colour_left().at<cv::Vec3b>(5, 7)[1] == 22);
  REQUIRE(f.scan.size() == 2);
  CHECK(f.scan[1].x == 20.0F);
  CHECK(f.scan[1].intensity == 0.25F);
  CHECK(f.T_world_cam0->translation().z() == 2.0);
  CHECK_THROWS_WITH(seq->load(3), Contains("frame 3 requested, the sequence has 3"));
}

TEST_CASE("check_sequence lists every file that does not load, sensor by sensor", "[io][kitti][bad-input]") {
  rgbl::test::SyntheticKitti kitti(4, 4);
  const auto seq = rgbl::open_kitti_odometry(kitti.dir);
  std::vector<std::size_t> progress;
  CHECK(rgbl::check_sequence(*seq, [&](std::size_t done, std::size_t total) {
          CHECK(total == 4);
          progress.push_back(done);
        }).empty());
  CHECK(progress == std::vector<std::size_t>{1, 2, 3, 4});

  // frame 1: both its image and its scan are bad, and both are listed; frame 3: the colour image only
  std::ofstream(kitti.image0(1)) << "not a PNG";
  std::ofstream(kitti.scan(1)) << "twenty bytes of junk";
  std::filesystem::remove(kitti.dir / "image_2" / "000003.png");
  const std::vector<rgbl::LoadProblem> problems = rgbl::check_sequence(*seq);
  REQUIRE(problems.size() == 3);
  CHECK(problems[0].frame == 1);
  CHECK_THAT(problems[0].message, Contains("image_0/000001.png"));
  CHECK(problems[1].frame == 1);
  CHECK_THAT(problems[1].message, Contains("velodyne/000001.bin"));
  CHECK(problems[2].frame == 3);
  CHECK_THAT(problems[2].message, Contains("image_2/000003.png"));
}

TEST_CASE("KITTI loader: bad input names the file", "[io][kitti][bad-input]") {
  SECTION(".bin size not a multiple of 16") {
    rgbl::test::SyntheticKitti kitti;
    rgbl::test::write_bin(kitti.scan(1), {1.0F, 2.0F, 3.0F, 4.0F, 5.0F});
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_NOTHROW(seq->load(0));
    CHECK_THAT(parse_error_message([&] { seq->load(1); }, kitti.scan(1)), Contains("not a multiple of 16"));
  }
  SECTION("an empty scan and non-finite points load as they are (the depth sources skip them)") {
    rgbl::test::SyntheticKitti kitti;
    rgbl::test::write_bin(kitti.scan(0), {});
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    rgbl::test::write_bin(kitti.scan(1), {nan, 0.0F, 0.0F, 1.0F, inf, 1.0F, 2.0F, 0.5F, 3.0F, 4.0F, 5.0F, 0.25F});
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK(seq->load(0).scan.empty());
    const auto scan = seq->load(1).scan;
    REQUIRE(scan.size() == 3);
    CHECK(std::isnan(scan[0].x));
    CHECK(std::isinf(scan[1].x));
    CHECK(scan[2].z == 5.0F);
  }
  SECTION("missing frame in the middle") {
    rgbl::test::SyntheticKitti kitti;
    std::filesystem::remove(kitti.image0(1));
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.image0(1)),
               Contains("missing: frame 1 of 0..2"));
  }
  SECTION("missing scan in the middle") {
    rgbl::test::SyntheticKitti kitti(4, 4);
    std::filesystem::remove(kitti.scan(2));
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.scan(2)),
               Contains("missing: frame 2"));
  }
  SECTION("times.txt with fewer or more rows than frames") {
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("sequences/07/times.txt", "0\n0.1\n");
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.dir / "times.txt"),
               Contains("has 2 timestamps, expected 3"));
    kitti.root.write("sequences/07/times.txt", "0\n0.1\n0.2\n0.3\n");
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.dir / "times.txt"),
               Contains("has 4 timestamps, expected 3"));
  }
  SECTION("non-numeric timestamp") {
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("sequences/07/times.txt", "0\nzero point one\n0.2\n");
    try {
      rgbl::open_kitti_odometry(kitti.dir);
      FAIL("no error");
    } catch (const rgbl::ParseError& e) {
      CHECK(e.file() == kitti.dir / "times.txt");
      CHECK(e.line() == 2);
    }
  }
  SECTION("fewer poses than frames") {
    rgbl::test::SyntheticKitti kitti(3, 2);
    const auto poses = kitti.root.path() / "poses" / "07.txt";
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, poses),
               Contains("has 2 poses, fewer than the 3 frames"));
  }
  SECTION("no ground truth is not an error") {
    rgbl::test::SyntheticKitti kitti(3, 0);
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_FALSE(seq->ground_truth());
    CHECK_FALSE(seq->load(0).T_world_cam0);
  }
  SECTION("malformed pose row") {
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("poses/07.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 x\n");
    try {
      rgbl::open_kitti_odometry(kitti.dir);
      FAIL("no error");
    } catch (const rgbl::ParseError& e) {
      CHECK(e.file() == kitti.root.path() / "poses" / "07.txt");
      CHECK(e.line() == 2);
    }
  }
  SECTION("an image whose size differs from the first image") {
    rgbl::test::SyntheticKitti kitti;
    rgbl::test::write_png(kitti.image0(2), 9, 6, 1, 0);
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_THAT(parse_error_message([&] { seq->load(2); }, kitti.image0(2)), Contains("image is 9x6, expected 8x6"));
  }
  SECTION("corrupt PNG") {
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("sequences/07/image_0/000001.png", "this is not a PNG at all");
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_THAT(parse_error_message([&] { seq->load(1); }, kitti.image0(1)), Contains("not a PNG or JPEG file"));
  }
  SECTION("a DICOM file named .png is refused before any decoder sees it") {
    // cv::imread chooses the decoder by content; GDCM's aborted the process on this one (found by
    // fuzz_image): 128 bytes of preamble, "DICM", then nothing it can read
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("sequences/07/image_0/000001.png", std::string(128, '\0') + "DICM\x02\x00\x01");
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_THAT(parse_error_message([&] { seq->load(1); }, kitti.image0(1)), Contains("not a PNG or JPEG file"));
  }
  SECTION("truncated PNG") {
    rgbl::test::SyntheticKitti kitti;
    std::string bytes;
    {
      std::ifstream in(kitti.image0(1), std::ios::binary);
      bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    kitti.root.write("sequences/07/image_0/000001.png", bytes.substr(0, bytes.size() / 2));
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_THAT(parse_error_message([&] { seq->load(1); }, kitti.image0(1)), Contains("cannot read or decode"));
  }
  SECTION("corrupt first image fails at opening") {
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("sequences/07/image_0/000000.png", "\x89PNG\r\n\x1a\n broken");
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.image0(0)),
               Contains("cannot read or decode"));
  }
  SECTION("unreadable paths") {
    rgbl::test::TempDir tmp;
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(tmp.path() / "nope"); }, tmp.path() / "nope"),
               Contains("not a folder"));
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(tmp.path()); }, tmp.path() / "calib.txt"),
               Contains("missing"));
    CHECK_THAT(parse_error_message([&] { rgbl::open_sequence(tmp.path()); }, tmp.path()),
               Contains("cannot tell the dataset format"));
    CHECK_THAT(parse_error_message([&] { rgbl::open_sequence(tmp.path() / "x"); }, tmp.path() / "x"),
               Contains("not a folder"));
    // a scan path that is a folder
    rgbl::test::SyntheticKitti kitti;
    std::filesystem::remove(kitti.scan(1));
    std::filesystem::create_directories(kitti.scan(1));
    const auto seq = rgbl::open_kitti_odometry(kitti.dir);
    CHECK_THROWS_AS(seq->load(1), rgbl::ParseError);
  }
  SECTION("calibration with a non-numeric value") {
    rgbl::test::SyntheticKitti kitti;
    kitti.root.write("sequences/07/calib.txt", "P0: 50 0 3.5 0 0 fifty 2.5 0 0 0 1 0\n");
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.dir / "calib.txt"),
               Contains("P0"));
  }
  SECTION("no frames at all") {
    rgbl::test::SyntheticKitti kitti(0, 0);
    CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.dir), Contains("no frames"));
  }
}

TEST_CASE("KITTI loader: times.txt must increase strictly, BOM skipped, FIFOs refused, not read", "[io][kitti][bad-input]") {
  rgbl::test::SyntheticKitti kitti;
  const auto times = kitti.dir / "times.txt";
  // duplicate and decreasing times used to pass, and the TUM trajectory written then was refused by rgbl eval
  kitti.root.write("sequences/07/times.txt", "0.0\n0.1\n0.1\n");
  CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, times),
             Contains("times.txt:3: timestamp 0.1 is not after the one on line 2 (0.1)"));
  kitti.root.write("sequences/07/times.txt", "0.0\n0.2\n\n0.1\n");
  CHECK_THAT(parse_error_message([&] { rgbl::read_kitti_times(times); }, times),
             Contains("times.txt:4: timestamp 0.1 is not after the one on line 2 (0.2)"));
  kitti.root.write("sequences/07/times.txt", "0.0\n0.1\nnan\n");
  CHECK_THAT(parse_error_message([&] { rgbl::read_kitti_times(times); }, times), Contains("times.txt:3:"));
  kitti.root.write("sequences/07/times.txt", "\xEF\xBB\xBF" "0.0\n0.1\n0.2\n");
  CHECK(rgbl::open_kitti_odometry(kitti.dir)->size() == 3);
  // a FIFO as calib.txt or as a scan used to block forever
  std::filesystem::remove(kitti.dir / "calib.txt");
  REQUIRE(::mkfifo((kitti.dir / "calib.txt").c_str(), 0600) == 0);
  CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.dir / "calib.txt"),
             Contains("is not a regular file"));
  kitti.root.write("sequences/07/calib.txt.new", rgbl::test::kSmallCalib);
  std::filesystem::rename(kitti.dir / "calib.txt.new", kitti.dir / "calib.txt");
  std::filesystem::remove(kitti.scan(1));
  REQUIRE(::mkfifo(kitti.scan(1).c_str(), 0600) == 0);
  const auto seq = rgbl::open_kitti_odometry(kitti.dir);
  CHECK_THAT(parse_error_message([&] { seq->load(1); }, kitti.scan(1)), Contains("is not a regular file"));
}

TEST_CASE("KITTI loader: intrinsics implausible for the images' size name calib.txt", "[io][kitti][bad-input]") {
  rgbl::test::SyntheticKitti kitti;
  // fx = fy = 1000 px on 8x6 images: a 0.46 degree field of view
  kitti.root.write("sequences/07/calib.txt", "P0: 1000 0 3.5 0 0 1000 2.5 0 0 0 1 0\n"
                                              "P1: 50 0 3.5 -25 0 50 2.5 0 0 0 1 0\n"
                                              "P2: 50 0 3.5 3 0 50 2.5 0 0 0 1 0\n"
                                              "P3: 50 0 3.5 -22 0 50 2.5 0 0 0 1 0\n"
                                              "Tr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n");
  CHECK_THAT(parse_error_message([&] { rgbl::open_kitti_odometry(kitti.dir); }, kitti.dir / "calib.txt"),
             Contains("camera 0: focal lengths fx 1000 fy 1000 px are implausible for a 8x6 image"));
}
