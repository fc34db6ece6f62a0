#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "support/data.hpp"

using Catch::Matchers::Contains;

namespace {

constexpr int kWidth = 320, kHeight = 120;
constexpr double kFx = 100.0, kBaseline = 0.5;  // fx * b = 50 px m

rgbl::DepthSourceContext settings() {
  rgbl::DepthSourceContext s;
  s.calibration.camera.fx = s.calibration.camera.fy = kFx;
  s.calibration.camera.cx = kWidth / 2.0;
  s.calibration.camera.cy = kHeight / 2.0;
  s.calibration.camera.width = kWidth;
  s.calibration.camera.height = kHeight;
  s.stereo_baseline = kBaseline;
  return s;
}

// A smooth random texture (blurred noise), wider than the image so that it can be shifted.
cv::Mat texture(int cols, int rows, unsigned seed) {
  cv::Mat noise(rows, cols, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.2);
  cv::normalize(noise, noise, 10.0, 245.0, cv::NORM_MINMAX);
  return noise;
}

// Left = texture columns [40, 40 + W); right sees the same scene `disparity` px further left:
// right(x) = texture(40 + x + disparity), linearly interpolated for fractional disparities.
rgbl::SensorFrame shifted_pair(const cv::Mat& tex, double disparity) {
  rgbl::SensorFrame frame;
  tex.colRange(40, 40 + kWidth).convertTo(frame.image, CV_8UC1);
  cv::Mat map_x(kHeight, kWidth, CV_32FC1), map_y(kHeight, kWidth, CV_32FC1);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      map_x.at<float>(y, x) = static_cast<float>(40.0 + x + disparity);
      map_y.at<float>(y, x) = static_cast<float>(y);
    }
  }
  cv::Mat right;
  cv::remap(tex, right, map_x, map_y, cv::INTER_LINEAR);
  right.convertTo(frame.image_right, CV_8UC1);
  return frame;
}

float disparity_of(const rgbl::KeypointDepth& d) { return static_cast<float>(kFx * kBaseline) / d.z; }

}  // namespace

TEST_CASE("stereo_sparse: created by name, options validated") {
  const auto registry = rgbl::builtin_depth_sources();
  REQUIRE(registry.contains("stereo_sparse"));
  auto source = registry.create("stereo_sparse", settings());
  CHECK(source->name() == "stereo_sparse");

  auto s = settings();
  s.stereo_baseline = 0.0;
  CHECK_THROWS_WITH(registry.create("stereo_sparse", s), Contains("stereo_baseline"));
  CHECK_THROWS_WITH(registry.create("stereo_sparse:fast", settings()), Contains("without an argument"));
  const auto bad = [](auto change) {
    rgbl::StereoSparseSourceOptions o;
    change(o);
    return o;
  };
  CHECK_THROWS_WITH(rgbl::make_stereo_sparse_source(bad([](auto& o) { o.window = 10; }), settings()),
                    Contains("stereo_sparse.window"));
  CHECK_THROWS_WITH(rgbl::make_stereo_sparse_source(bad([](auto& o) { o.max_disparity = 2; }), settings()),
                    Contains("stereo_sparse.max_disparity"));
  CHECK_THROWS_WITH(rgbl::make_stereo_sparse_source(bad([](auto& o) { o.uniqueness_ratio = 100; }), settings()),
                    Contains("stereo_sparse.uniqueness_ratio"));
  // a registry entry starts from its options
  auto with_options = rgbl::builtin_depth_sources();
  with_options.add("stereo_sparse", rgbl::stereo_sparse_depth_source(bad([](auto& o) { o.window = 10; })));
  CHECK_THROWS_WITH(with_options.create("stereo_sparse", settings()), Contains("stereo_sparse.window"));
  CHECK(with_options.entry("stereo_sparse").needs.right_image);
  CHECK_FALSE(with_options.entry("stereo_sparse").needs.scan);
}

TEST_CASE("stereo_sparse: exact disparity on a shifted texture") {
  auto source = rgbl::builtin_depth_sources().create("stereo_sparse", settings());
  const cv::Mat tex = texture(kWidth + 200, kHeight, 5);
  std::vector<Eigen::Vector2f> pixels;
  for (int y = 12; y < kHeight - 12; y += 9) {
    for (float x = 150.0F; x < kWidth - 10; x += 13.0F) pixels.emplace_back(x, static_cast<float>(y));
  }
  pixels.emplace_back(200.4F, 50.6F);  // sub-pixel keypoint positions round to the nearest pixel
  std::vector<rgbl::KeypointDepth> out(pixels.size());
  for (const double disparity : {4.0, 7.0, 12.0, 20.5, 31.0, 55.25, 100.0}) {
    CAPTURE(disparity);
    source->prepare(shifted_pair(tex, disparity));
    source->sample(pixels, out);
    int matched = 0;
    double worst = 0.0, sum_error = 0.0;
    for (const auto& d : out) {
      if (d.z <= 0.0F) continue;
      ++matched;
      worst = std::max(worst, std::abs(disparity_of(d) - disparity));
      sum_error += std::abs(disparity_of(d) - disparity);
      CHECK(d.sample_distance_px == 0.0F);
      // spread = z(d - 0.5) - z(d + 0.5)
      CHECK(d.spread == Approx(50.0 / (disparity - 0.5) - 50.0 / (disparity + 0.5)).epsilon(0.05));
    }
    CHECK(matched >= static_cast<int>(pixels.size()) * 95 / 100);
    CHECK(sum_error / matched < 0.04);
    // a parabola through SSD costs is exact at integer and half-pixel shifts; in between the
    // interpolated texture is not quite quadratic (measured worst 0.11 px at a quarter pixel)
    CHECK(worst < (disparity == 55.25 ? 0.12 : 0.1));
  }
}

TEST_CASE("stereo_sparse: no depth on flat or repetitive patches, near borders or beyond the range") {
  auto source = rgbl::builtin_depth_sources().create("stereo_sparse", settings());
  cv::Mat tex = texture(kWidth + 200, kHeight, 9);
  tex(cv::Rect(40 + 150, 20, 80, 60)).setTo(128.0F);  // flat in the left image and in the right
  for (int x = 40 + 240; x < 40 + 300; ++x) tex.col(x).setTo(x % 6 < 3 ? 60.0F : 190.0F);  // stripes, period 6
  source->prepare(shifted_pair(tex, 10.0));
  const std::vector<Eigen::Vector2f> pixels = {
      {190.0F, 50.0F},  // flat
      {265.0F, 50.0F},  // stripes: every 6 px of disparity matches equally
      {2.0F, 50.0F},    // window leaves the image
      {100.0F, 1.0F},   // window leaves the image
      {100.0F, 50.0F},  // textured: the control
  };
  std::vector<rgbl::KeypointDepth> out(pixels.size());
  source->sample(pixels, out);
  CHECK(out[0].z == 0.0F);
  CHECK(out[1].z == 0.0F);
  CHECK(out[2].z == 0.0F);
  CHECK(out[3].z == 0.0F);
  CHECK(out[4].z == Approx(5.0).epsilon(0.01));

  // disparity 150 is beyond max_disparity 128: the search must not return a wrong depth for most
  source->prepare(shifted_pair(texture(kWidth + 300, kHeight, 13), 150.0));
  std::vector<Eigen::Vector2f> grid;
  for (int y = 12; y < kHeight - 12; y += 10) {
    for (int x = 160; x < kWidth - 10; x += 10) grid.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }
  std::vector<rgbl::KeypointDepth> far(grid.size());
  source->sample(grid, far);
  const auto with_depth = std::count_if(far.begin(), far.end(), [](const auto& d) { return d.z > 0.0F; });
  CHECK(with_depth <= static_cast<long>(grid.size()) / 10);
}

TEST_CASE("stereo_sparse: bad input is named") {
  auto source = rgbl::builtin_depth_sources().create("stereo_sparse", settings());
  const rgbl::SensorFrame pair = shifted_pair(texture(kWidth + 200, kHeight, 3), 10.0);
  rgbl::SensorFrame frame;
  frame.image = pair.image;
  CHECK_THROWS_AS(source->prepare(frame), rgbl::ConfigError);
  CHECK_THROWS_WITH(source->prepare(frame), Contains("frame.image_right") && Contains("stereo pair"));
  frame.image_right = cv::Mat(10, 10, CV_8UC1, cv::Scalar(0));
  CHECK_THROWS_WITH(source->prepare(frame), Contains("frame.image_right") && Contains("320x120"));
  frame.image_right = cv::Mat(kHeight, kWidth, CV_16UC1, cv::Scalar(0));
  CHECK_THROWS_WITH(source->prepare(frame), Contains("8-bit"));
  // colour pairs are converted
  rgbl::SensorFrame colour;
  cv::cvtColor(pair.image, colour.image, cv::COLOR_GRAY2BGR);
  cv::cvtColor(pair.image_right, colour.image_right, cv::COLOR_GRAY2BGR);
  source->prepare(colour);
  const std::vector<Eigen::Vector2f> pixel = {{200.0F, 60.0F}};
  std::vector<rgbl::KeypointDepth> out(1);
  source->sample(pixel, out);
  CHECK(out[0].z == Approx(5.0).epsilon(0.01));
  // the dense map is matched on a grid on demand
  const cv::Mat_<float> dense = source->dense_depth();
  CHECK(dense(60, 200) == Approx(5.0).epsilon(0.01));
  CHECK(dense(61, 200) == 0.0F);
}

TEST_CASE("stereo_sparse on real KITTI frames: exact on a shifted real image, close to the LiDAR on the pair") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  const auto kitti = rgbl::read_kitti_odometry_calibration(*seq / "calib.txt", 1226, 370);
  rgbl::DepthSourceContext s;
  s.calibration = kitti.camera(0);
  s.stereo_baseline = kitti.baseline(0, 1);
  const double fb = s.calibration.camera.fx * s.stereo_baseline;
  const auto registry = rgbl::builtin_depth_sources();
  auto stereo = registry.create("stereo_sparse", s);
  auto lidar = registry.create("lidar", s);
  const auto scan = rgbl::read_kitti_scan(*seq / "velodyne/000000.bin");
  rgbl::SensorFrame frame;
  frame.image = rgbl::read_image_file(*seq / "image_0/000000.png", rgbl::ImageMode::grey);
  frame.image_right = rgbl::read_image_file(*seq / "image_1/000000.png", rgbl::ImageMode::grey);
  frame.scan = scan;
  REQUIRE(!frame.image.empty());
  REQUIRE(!frame.image_right.empty());
  std::vector<Eigen::Vector2f> pixels;
  for (int y = 130; y < 360; y += 4) {
    for (int x = 10; x < 1216; x += 4) pixels.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }

  // the real left image shifted by exactly 20 px: every match within 0.1 px
  {
    rgbl::SensorFrame shifted;
    shifted.image = frame.image;
    shifted.image_right = cv::Mat(frame.image.size(), CV_8UC1, cv::Scalar(0));
    frame.image.colRange(20, frame.image.cols).copyTo(shifted.image_right.colRange(0, frame.image.cols - 20));
    stereo->prepare(shifted);
    std::vector<rgbl::KeypointDepth> z(pixels.size());
    stereo->sample(pixels, z);
    std::vector<double> error;
    for (const auto& d : z) {
      if (d.z > 0.0F) error.push_back(std::abs(fb / d.z - 20.0));
    }
    REQUIRE(error.size() > pixels.size() / 3);
    std::sort(error.begin(), error.end());
    CHECK(error[error.size() / 2] < 0.02);
    CHECK(error[error.size() * 9 / 10] < 0.1);
  }

  lidar->prepare(frame);
  std::vector<rgbl::KeypointDepth> zl(pixels.size());
  lidar->sample(pixels, zl);
  // |dz|/z against the LiDAR: close range (what the tracker uses), near a real LiDAR sample, off LiDAR
  // depth edges; returns the count, median and 75th percentile
  const auto compare = [&](const rgbl::DepthSource& source) {
    std::vector<rgbl::KeypointDepth> zs(pixels.size());
    source.sample(pixels, zs);
    std::vector<double> relative;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      if (zs[i].z <= 0.0F || zl[i].z <= 0.0F || zl[i].z > 20.0F || zl[i].sample_distance_px > 1.5F) continue;
      if (zl[i].spread > 0.5F) continue;
      relative.push_back(std::abs(zs[i].z - zl[i].z) / zl[i].z);
    }
    std::sort(relative.begin(), relative.end());
    if (relative.empty()) relative.push_back(1.0);
    return std::array<double, 3>{static_cast<double>(relative.size()), relative[relative.size() / 2],
                                 relative[relative.size() * 3 / 4]};
  };
  stereo->prepare(frame);
  const auto plain = compare(*stereo);
  INFO("stereo_sparse vs LiDAR, frame 0: " << plain[0] << " points, median |dz|/z " << plain[1] << ", p75 "
                                           << plain[2]);
  CHECK(plain[0] > 1000);
  CHECK(plain[1] < 0.035);
  CHECK(plain[2] < 0.08);

  // the left-right check drops some of the disagreeing matches
  rgbl::StereoSparseSourceOptions checked_options;
  checked_options.left_right_check = true;
  auto checked_source = rgbl::make_stereo_sparse_source(checked_options, s);
  checked_source->prepare(frame);
  const auto checked = compare(*checked_source);
  INFO("with the left-right check: " << checked[0] << " points, median " << checked[1] << ", p75 " << checked[2]);
  CHECK(checked[0] < plain[0]);
  CHECK(checked[0] > 0.9 * plain[0]);
  CHECK(checked[2] < plain[2]);
}
