#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/io/sequence.hpp"
#include "support/temp_dir.hpp"
#include "synthetic.hpp"

#include <catch2/catch.hpp>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

// rgbd_dataset_freiburg1_tiny: 4 rgb images (8x6) at 30 Hz, depth 5 ms later except for the third,
// which has none within 20 ms; ground truth at 100 Hz moving 1 m/s along x and turning
// 0.5 rad/s about z.
struct SyntheticTum {
  rgbl::test::TempDir tmp;
  std::filesystem::path dir;

  SyntheticTum() {
    dir = tmp.path() / "rgbd_dataset_freiburg1_tiny";
    std::string rgb = "# color images\n# file: 'x'\n# timestamp filename\n";
    std::string depth = "# depth maps\n# file: 'x'\n# timestamp filename\n";
    for (int i = 0; i < 4; ++i) {
      const double t = 100.0 + i / 30.0;
      rgb += fmt::format("{:.6f} rgb/{:.6f}.png\n", t, t);
      rgbl::test::write_png(dir / "rgb" / fmt::format("{:.6f}.png", t), 8, 6, 3, 40 * i);
      if (i == 2) continue;
      const double td = t + 0.005;
      depth += fmt::format("{:.6f} depth/{:.6f}.png\n", td, td);
      cv::Mat_<std::uint16_t> d(6, 8, static_cast<std::uint16_t>(5000 * (i + 1)));
      d(0, 0) = 0;
      std::filesystem::create_directories(dir / "depth");
      cv::imwrite((dir / "depth" / fmt::format("{:.6f}.png", td)).string(), d);
    }
    tmp.write("rgbd_dataset_freiburg1_tiny/rgb.txt", rgb);
    tmp.write("rgbd_dataset_freiburg1_tiny/depth.txt", depth);
    std::string gt = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
    for (int k = 0; k <= 12; ++k) {
      const double t = 99.99 + 0.01 * k;
      const double yaw = 0.5 * (t - 100.0);
      gt += fmt::format("{:.4f} {} 0 0 0 0 {} {}\n", t, t - 100.0, std::sin(yaw / 2), std::cos(yaw / 2));
    }
    tmp.write("rgbd_dataset_freiburg1_tiny/groundtruth.txt", gt);
  }
};

}  // namespace

TEST_CASE("TUM RGB-D: association, depth in metres, interpolated ground truth", "[io][tum]") {
  SyntheticTum tum;
  const auto seq = rgbl::open_sequence(tum.dir);
  CHECK(seq->format() == rgbl::DatasetFormat::tum);
  REQUIRE(seq->size() == 3);  // the third rgb image has no depth within 20 ms
  CHECK_THAT(seq->notes().at(0), Contains("3 of 4 rgb images"));
  CHECK_THAT(seq->timestamp(2), WithinAbs(100.1, 1e-6));
  CHECK(seq->calibration().P[0](0, 0) == 517.3);  // freiburg1 from the folder name
  CHECK(seq->calibration().width[2] == 8);
  CHECK(seq->calibration().height[0] == 6);
  CHECK(seq->sensors().depth);

  const auto f = seq->load(2);
  CHECK(f.colour_left().at<cv::Vec3b>(1, 1)[0] == 120);
  CHECK(f.grey_left().type() == CV_8UC1);
  CHECK(f.grey_left().at<std::uint8_t>(1, 1) == 120);
  CHECK(f.depth(1, 1) == 4.0F);  // 20000 / 5000
  CHECK(f.depth(0, 0) == 0.0F);

  // The ground truth starts at 99.99 and ends at 100.11: all three frames are inside.
  REQUIRE(seq->ground_truth());
  REQUIRE(seq->ground_truth()->size() == 3);
  REQUIRE(f.T_world_cam0);
  CHECK_THAT(f.T_world_cam0->translation().x(), WithinAbs(0.1, 1e-9));
  CHECK_THAT(rgbl::rotation_angle(f.T_world_cam0->linear()), WithinAbs(0.05, 1e-9));
  const auto g = seq->load(1);
  CHECK_THAT(g.T_world_cam0->translation().x(), WithinAbs(1.0 / 30.0, 1e-6));  // between samples
  CHECK_THAT(rgbl::rotation_angle(g.T_world_cam0->linear()), WithinAbs(0.5 / 30.0, 1e-6));
}

TEST_CASE("TUM loader: bad input names the file", "[io][tum][bad-input]") {
  SECTION("listed image missing") {
    SyntheticTum tum;
    const auto file = tum.dir / "rgb" / fmt::format("{:.6f}.png", 100.0 + 1 / 30.0);
    std::filesystem::remove(file);
    CHECK_THROWS_WITH(rgbl::open_tum_rgbd(tum.dir), Contains(file.string()) && Contains("listed in rgb.txt line 5"));
  }
  SECTION("non-numeric timestamp") {
    SyntheticTum tum;
    const auto list = tum.tmp.write("rgbd_dataset_freiburg1_tiny/rgb.txt", "100.0 rgb/100.000000.png\nabc rgb/x.png\n");
    CHECK_THROWS_WITH(rgbl::open_tum_rgbd(tum.dir), Contains(list.string() + ":2:"));
  }
  SECTION("malformed ground truth row") {
    SyntheticTum tum;
    const auto gt = tum.tmp.write("rgbd_dataset_freiburg1_tiny/groundtruth.txt", "100 0 0 0 0 0 0 1\n101 0 0\n");
    CHECK_THROWS_WITH(rgbl::open_tum_rgbd(tum.dir), Contains(gt.string() + ":2:"));
  }
  SECTION("corrupt depth image") {
    SyntheticTum tum;
    const auto file = tum.dir / "depth" / fmt::format("{:.6f}.png", 100.005);
    tum.tmp.write(std::filesystem::relative(file, tum.tmp.path()).string(), "garbage");
    const auto seq = rgbl::open_tum_rgbd(tum.dir);
    CHECK_THROWS_WITH(seq->load(0), Contains(file.string()) && Contains("not a PNG or JPEG file"));
  }
  SECTION("no rgb.txt") {
    rgbl::test::TempDir tmp;
    CHECK_THROWS_WITH(rgbl::open_tum_rgbd(tmp.path()), Contains("rgb.txt") && Contains("missing"));
  }
  SECTION("bad options") {
    SyntheticTum tum;
    rgbl::TumOptions options;
    options.depth_factor = 0.0;
    CHECK_THROWS_AS(rgbl::open_tum_rgbd(tum.dir, options), rgbl::ConfigError);
  }
}
