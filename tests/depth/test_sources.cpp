#include "rgbl/core/error.hpp"
#include "rgbl/depth/completion.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/se3.hpp"
#include "support/data.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

using Catch::Matchers::Contains;

namespace {

// LiDAR frame == camera frame, f = 100 px, 64x48 image, principal point (32, 24).
rgbl::DepthSourceContext simple_settings() {
  rgbl::DepthSourceContext s;
  s.calibration.camera.fx = s.calibration.camera.fy = 100.0;
  s.calibration.camera.cx = 32.0;
  s.calibration.camera.cy = 24.0;
  s.calibration.camera.width = 64;
  s.calibration.camera.height = 48;
  return s;
}

rgbl::LidarSourceOptions simple_lidar() {
  rgbl::LidarSourceOptions o;
  o.projection.min_depth = 1.0F;
  return o;
}

rgbl::DepthSourceContext kitti_settings(const std::filesystem::path& seq) {
  const auto kitti = rgbl::read_kitti_odometry_calibration(seq / "calib.txt", 1226, 370);
  rgbl::DepthSourceContext s;
  s.calibration = kitti.camera(2);
  s.stereo_baseline = kitti.baseline(2, 3);
  return s;
}

class ConstantSource final : public rgbl::DepthSource {
 public:
  explicit ConstantSource(float z) : z_(z) {}
  std::string_view name() const override { return "constant"; }
  void prepare(const rgbl::SensorFrame&) override {}
  void sample(std::span<const Eigen::Vector2f>, std::span<rgbl::KeypointDepth> out) const override {
    for (auto& k : out) k.z = z_;
  }
  cv::Mat_<float> dense_depth() const override { return {}; }

 private:
  float z_;
};

}  // namespace

TEST_CASE("registry: built-ins, unknown names and user sources") {
  auto registry = rgbl::builtin_depth_sources();
  CHECK(registry.names() == std::vector<std::string>{"lidar", "precomputed", "rgbd", "stereo", "stereo_sparse"});
  try {
    (void)registry.create("neural", simple_settings());
    FAIL("expected a ConfigError");
  } catch (const rgbl::ConfigError& e) {
    CHECK(e.key() == "--depth");
    CHECK_THAT(e.what(), Contains("lidar[:") && Contains("precomputed:<") && Contains("stereo_sparse") &&
                             Contains("'neural'"));
  }
  // what each built-in reads from a frame
  CHECK(registry.entry("lidar:diamond7").needs.scan);
  CHECK(registry.entry("rgbd").needs.depth_image);
  CHECK(registry.entry("stereo").needs.right_image);
  CHECK_FALSE(registry.entry("precomputed:x").needs.scan);
  // a user source with its own option in the argument
  registry.add("constant", {{}, "constant[:<metres>]", [](std::string_view arg, const rgbl::DepthSourceContext&) {
                              return std::make_unique<ConstantSource>(arg.empty() ? 4.0F : std::stof(std::string(arg)));
                            }});
  CHECK(registry.create("constant:2.5", simple_settings())->name() == "constant");
  auto source = registry.create("constant", simple_settings());
  REQUIRE(source != nullptr);
  CHECK(source->name() == "constant");
  const std::vector<Eigen::Vector2f> pixels = {{1.0F, 2.0F}};
  std::vector<rgbl::KeypointDepth> out(1);
  source->sample(pixels, out);
  CHECK(out[0].z == 4.0F);
  CHECK_THROWS_AS(registry.add("", {}), rgbl::ConfigError);
  CHECK_THROWS_AS(registry.add("a:b", rgbl::lidar_depth_source()), rgbl::ConfigError);
  CHECK_THROWS_WITH(registry.create("lidar:hexagon3", simple_settings()), Contains("--depth") && Contains("hexagon3"));
  CHECK_THROWS_WITH(registry.create("lidar:diamond4", simple_settings()), Contains("odd kernel size"));
  CHECK_THROWS_WITH(registry.create("precomputed", simple_settings()), Contains("precomputed:<folder"));
  CHECK_THROWS_WITH(registry.create("rgbd:x", simple_settings()), Contains("without an argument"));
  auto bad = simple_settings();
  bad.calibration.camera.fx = 0.0;
  CHECK_THROWS_AS(registry.create("lidar", bad), rgbl::ConfigError);
}

TEST_CASE("lidar source: projects, samples keypoints and agrees with its dense map") {
  auto source = rgbl::make_lidar_source(simple_lidar(), simple_settings());
  CHECK(source->name() == "lidar");
  {
    // A dropped scan (empty) is no depth anywhere, not an error that would stop a run.
    source->prepare({});
    const std::vector<Eigen::Vector2f> anywhere = {{32.0F, 24.0F}, {5.0F, 5.0F}};
    std::vector<rgbl::KeypointDepth> none(anywhere.size(), rgbl::KeypointDepth{7.0F});
    source->sample(anywhere, none);
    CHECK(none[0].z == 0.0F);
    CHECK(none[1].z == 0.0F);
    CHECK(cv::countNonZero(source->dense_depth()) == 0);
  }
  const std::vector<rgbl::LidarPoint> scan = {{0.0F, 0.0F, 10.0F, 0.0F}, {0.3F, 0.0F, 20.0F, 0.0F}};  // (32,24), (33.5->34,24)
  rgbl::SensorFrame frame;
  frame.scan = scan;
  source->prepare(frame);
  const std::vector<Eigen::Vector2f> pixels = {{33.0F, 24.0F}, {36.0F, 24.0F}, {10.0F, 10.0F}};
  std::vector<rgbl::KeypointDepth> out(pixels.size());
  source->sample(pixels, out);
  CHECK(out[0].z == 10.0F);
  CHECK(out[0].sample_distance_px == Approx(1.0F));
  CHECK(out[0].spread == Approx(10.0F));
  CHECK(out[1].z == 20.0F);
  CHECK(out[1].sample_distance_px == Approx(2.0F));
  CHECK(out[2].z == 0.0F);
  const cv::Mat_<float> dense = source->dense_depth();
  CHECK(cv::countNonZero(dense) == 13 + 13 - 5);  // two diamonds 2 px apart share 5 cells
  CHECK(dense(24, 33) == 10.0F);
  CHECK(dense(24, 35) == 20.0F);
}

TEST_CASE("lidar source on real frames: keypoint samples equal the dense map (dilated) or lie on its surface") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  auto settings = kitti_settings(*seq);
  const auto scan = rgbl::read_kitti_scan(*seq / "velodyne" / "000010.bin");
  rgbl::SensorFrame frame;
  frame.index = 10;
  frame.scan = scan;
  const int width = settings.calibration.camera.width, height = settings.calibration.camera.height;
  std::vector<Eigen::Vector2f> pixels;
  for (int y = 0; y < height; y += 3)
    for (int x = 0; x < width; x += 2) pixels.emplace_back(static_cast<float>(x) + 0.3F, static_cast<float>(y) - 0.4F);
  // the rules as such: the surface mean without the ring plane fit (0.5 deg by default, checked below)
  auto sample = [&](rgbl::KeypointDepthRule rule, cv::Mat_<float>& dense, double fit_deg = 0.0) {
    rgbl::LidarSourceOptions options;
    options.keypoint_depth = rule;
    options.surface_fit_window_deg = fit_deg;
    auto source = rgbl::make_lidar_source(options, settings);
    source->prepare(frame);
    dense = source->dense_depth();
    std::vector<rgbl::KeypointDepth> out(pixels.size());
    source->sample(pixels, out);
    return out;
  };
  cv::Mat_<float> dense, dense_surface;
  const auto dilated = sample(rgbl::KeypointDepthRule::dilated, dense);
  const auto surface = sample(rgbl::KeypointDepthRule::surface_mean, dense_surface);
  CHECK(rgbl::depth_density(dense) > 0.2);
  REQUIRE(dense.size() == cv::Size(width, height));
  std::size_t mismatches = 0, with_depth = 0, off_surface = 0, changed = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float expected = dense(static_cast<int>(std::floor(pixels[i].y() + 0.5F)), static_cast<int>(std::floor(pixels[i].x() + 0.5F)));
    mismatches += std::memcmp(&expected, &dilated[i].z, sizeof(float)) != 0 ? 1U : 0U;
    CHECK((surface[i].z > 0.0F) == (dilated[i].z > 0.0F));  // the same pixels have depth
    if (dilated[i].z > 0.0F) {
      ++with_depth;
      // the farthest diamond cell from (x + 0.3, y - 0.4) is (x, y + 2)
      CHECK(dilated[i].sample_distance_px <= std::hypot(0.3F, 2.4F) + 1e-4F);
      CHECK(dilated[i].spread >= 0.0F);
      CHECK(surface[i].spread == dilated[i].spread);
      CHECK(surface[i].sample_distance_px <= std::hypot(0.3F, 2.4F) + 1e-4F);
      // the surface mean is never nearer than the minimum and stays on the nearest surface
      off_surface += surface[i].z < dilated[i].z - 1e-4F || surface[i].z > dilated[i].z + dilated[i].spread + 1e-4F ? 1U : 0U;
      changed += surface[i].z != dilated[i].z ? 1U : 0U;
    }
  }
  CHECK(bool(cv::norm(dense, dense_surface, cv::NORM_INF) == 0.0));  // the dense map is the paper's either way
  CHECK(mismatches == 0);
  CHECK(off_surface == 0);
  CHECK(changed > 0);
  CHECK(with_depth > pixels.size() / 5);

  // The ring plane fit (LiDAR.SurfaceFitWindowDeg 0.5, the default) moves only some keypoints (those on
  // the road between rings), never by more than its guard, 3 x the surface tolerance, from the surface mean.
  cv::Mat_<float> dense_fit;
  const auto fitted = sample(rgbl::KeypointDepthRule::surface_mean, dense_fit, 0.5);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    CHECK((fitted[i].z > 0.0F) == (surface[i].z > 0.0F));
    if (!(surface[i].z > 0.0F)) continue;
    CHECK(std::abs(fitted[i].z - surface[i].z) <= 3.0F * 0.05F * surface[i].z * 1.0001F);
    moved += std::abs(fitted[i].z - surface[i].z) > 1e-3F * surface[i].z ? 1U : 0U;
  }
  CHECK(moved > 0);
  CHECK(moved < with_depth / 2);
}

TEST_CASE("depth PNGs: depth x 256 rounded, 0 for no depth and for depths that do not fit") {
  rgbl::test::TempDir dir;
  cv::Mat_<float> depth(2, 4, 0.0F);
  depth(0, 0) = 10.5F;                                     // exact
  depth(0, 1) = 1.0F / 512.0F + 1e-4F;                     // rounds to 1 / 256
  depth(0, 2) = 255.99F;                                   // the largest that fits
  depth(0, 3) = 300.0F;                                    // does not fit: no depth, not a false 256 m
  depth(1, 0) = -2.0F;
  depth(1, 1) = std::numeric_limits<float>::quiet_NaN();
  depth(1, 2) = std::numeric_limits<float>::infinity();
  rgbl::write_depth_png(dir.path() / "d.png", depth);
  const cv::Mat_<float> back = rgbl::read_depth_png(dir.path() / "d.png");
  CHECK(back(0, 0) == 10.5F);
  CHECK(back(0, 1) == 1.0F / 256.0F);
  CHECK(back(0, 2) == Approx(255.99F).margin(1.0 / 512.0));
  for (const auto& [v, u] : {std::pair{0, 3}, {1, 0}, {1, 1}, {1, 2}, {1, 3}}) CHECK(back(v, u) == 0.0F);
  // the simulator's exact depth is written by the same encoder (rgbl::encode_depth16)
  const cv::Mat encoded = rgbl::encode_depth16(depth);
  CHECK(encoded.type() == CV_16UC1);
  CHECK(encoded.at<std::uint16_t>(0, 2) == 65533);
  CHECK(encoded.at<std::uint16_t>(0, 3) == 0);
}

TEST_CASE("precomputed source: reads PNGs, drops the top fraction and far depths, names missing files") {
  rgbl::test::TempDir dir;
  auto settings = simple_settings();
  rgbl::PrecomputedSourceOptions precomputed;
  precomputed.folder = dir.path();
  precomputed.ignore_top_fraction = 0.25;  // 12 of 48 rows
  precomputed.max_depth = 50.0F;
  cv::Mat_<float> depth(48, 64, 10.5F);
  depth(30, 10) = 60.0F;  // beyond the cap
  depth(30, 11) = 0.0F;
  rgbl::write_depth_png(dir.path() / "000007.png", depth);
  auto source = rgbl::make_precomputed_source(precomputed, settings);
  rgbl::SensorFrame frame;
  frame.index = 7;
  source->prepare(frame);
  const cv::Mat_<float> dense = source->dense_depth();
  CHECK(dense(11, 5) == 0.0F);
  CHECK(dense(12, 5) == 10.5F);  // 10.5 * 256 is exact in uint16
  CHECK(dense(30, 10) == 0.0F);
  CHECK(cv::countNonZero(dense) == 36 * 64 - 2);
  const std::vector<Eigen::Vector2f> pixels = {{5.2F, 20.0F}, {5.0F, 3.0F}};
  std::vector<rgbl::KeypointDepth> out(2);
  source->sample(pixels, out);
  CHECK(out[0].z == 10.5F);
  CHECK(out[0].sample_distance_px == Approx(0.2F));
  CHECK(out[0].spread == 0.0F);
  CHECK(out[1].z == 0.0F);

  frame.index = 8;
  CHECK_THROWS_WITH(source->prepare(frame), Contains("000008.png"));
  rgbl::write_depth_png(dir.path() / "000009.png", cv::Mat_<float>(10, 10, 1.0F));
  frame.index = 9;
  CHECK_THROWS_WITH(source->prepare(frame), Contains("000009.png") && Contains("64x48"));
  precomputed.ignore_top_fraction = 1.0;
  CHECK_THROWS_WITH(rgbl::make_precomputed_source(precomputed, settings), Contains("precomputed.ignore_top_fraction"));
  precomputed.folder.clear();
  precomputed.ignore_top_fraction = 0.0;
  CHECK_THROWS_WITH(rgbl::make_precomputed_source(precomputed, settings), Contains("precomputed.folder"));
  // by name the argument is the folder
  CHECK(rgbl::builtin_depth_sources().create("precomputed:" + dir.path().string(), settings)->name() == "precomputed");
}

TEST_CASE("rgbd source: scaled uint16 or float metres, bad input named") {
  auto settings = simple_settings();
  rgbl::RgbdSourceOptions rgbd;
  rgbd.scale = 5000.0;
  auto source = rgbl::make_rgbd_source(rgbd, settings);
  rgbl::SensorFrame frame;
  CHECK_THROWS_WITH(source->prepare(frame), Contains("frame.depth_image"));
  cv::Mat raw(48, 64, CV_16UC1, cv::Scalar(10000));  // 2 m at 5000 per metre
  raw.at<std::uint16_t>(5, 5) = 0;
  frame.depth_image = raw;
  source->prepare(frame);
  cv::Mat_<float> dense = source->dense_depth();
  CHECK(dense(10, 10) == Approx(2.0F));
  CHECK(dense(5, 5) == 0.0F);
  std::vector<rgbl::KeypointDepth> out(1);
  const std::vector<Eigen::Vector2f> pixels = {{5.0F, 4.0F}};
  source->sample(pixels, out);
  CHECK(out[0].z == Approx(2.0F));
  CHECK(out[0].spread == 0.0F);  // the hole at (5, 5) is not a depth
  frame.depth_image = cv::Mat(48, 64, CV_32FC1, cv::Scalar(std::nanf("")));
  source->prepare(frame);
  CHECK(cv::countNonZero(source->dense_depth()) == 0);
  frame.depth_image = cv::Mat(48, 64, CV_8UC1, cv::Scalar(1));
  CHECK_THROWS_WITH(source->prepare(frame), Contains("CV_16UC1"));
  frame.depth_image = cv::Mat(10, 10, CV_16UC1, cv::Scalar(1));
  CHECK_THROWS_WITH(source->prepare(frame), Contains("64x48"));
  rgbd.scale = 0.0;
  CHECK_THROWS_WITH(rgbl::make_rgbd_source(rgbd, settings), Contains("rgbd.scale"));
}

TEST_CASE("stereo source: depth = fx * baseline / disparity on a shifted texture") {
  auto settings = simple_settings();
  CHECK_THROWS_WITH(rgbl::builtin_depth_sources().create("stereo", settings), Contains("stereo_baseline"));
  settings.calibration.camera.width = 160;
  settings.calibration.camera.height = 80;
  settings.stereo_baseline = 0.5;
  rgbl::StereoSourceOptions stereo;
  stereo.num_disparities = 16;
  auto source = rgbl::make_stereo_source(stereo, settings);
  rgbl::SensorFrame frame;
  CHECK_THROWS_WITH(source->prepare(frame), Contains("image_right"));
  // a random texture seen 8 px further left in the right image: disparity 8, z = 100 * 0.5 / 8
  cv::Mat texture(80, 200, CV_8UC1);
  cv::randu(texture, 0, 255);
  frame.image = texture.colRange(20, 180).clone();
  frame.image_right = texture.colRange(28, 188).clone();
  source->prepare(frame);
  const cv::Mat_<float> dense = source->dense_depth();
  const std::vector<Eigen::Vector2f> pixels = {{100.0F, 40.0F}};
  std::vector<rgbl::KeypointDepth> out(1);
  source->sample(pixels, out);
  CHECK(out[0].z == Approx(100.0 * 0.5 / 8.0).epsilon(0.02));
  CHECK(rgbl::depth_density(dense.colRange(40, 150)) > 0.9);
  frame.image_right = cv::Mat(10, 10, CV_8UC1, cv::Scalar(0));
  CHECK_THROWS_WITH(source->prepare(frame), Contains("frame.image_right"));
}

TEST_CASE("stereo source: images no wider than the disparity range are refused before OpenCV aborts") {
  auto settings = simple_settings();
  settings.stereo_baseline = 0.5;
  settings.calibration.camera.height = 60;
  rgbl::StereoSourceOptions stereo;  // 128 disparities
  for (const int width : {100, 128}) {  // OpenCV aborted (SIGABRT) at 100 px, failed an assertion at 128
    settings.calibration.camera.width = width;
    CHECK_THROWS_WITH(rgbl::make_stereo_source(stereo, settings),
                      Contains("'--depth'") && Contains("stereo.num_disparities = 128 px") &&
                          Contains(std::to_string(width) + " px wide"));
  }
  settings.calibration.camera.width = 129;
  auto source = rgbl::make_stereo_source(stereo, settings);
  rgbl::SensorFrame frame;
  cv::Mat texture(60, 129, CV_8UC1);
  cv::randu(texture, 0, 255);
  frame.image = texture;
  frame.image_right = texture;
  CHECK_NOTHROW(source->prepare(frame));
}

TEST_CASE("lidar source with IP-Basic completion samples its dense map") {
  auto settings = simple_settings();
  auto lidar = simple_lidar();
  lidar.completion = rgbl::parse_completion_method("ip_basic_fast");
  CHECK_THROWS_WITH(rgbl::parse_completion_method("neural"), Contains("lidar.completion"));
  auto source = rgbl::make_lidar_source(lidar, settings);
  std::vector<rgbl::LidarPoint> scan;
  for (int y = -20; y <= 20; y += 4)
    for (int x = -30; x <= 30; x += 4) scan.push_back({static_cast<float>(x) * 0.2F, static_cast<float>(y) * 0.2F, 20.0F, 0.0F});
  rgbl::SensorFrame frame;
  frame.scan = scan;
  source->prepare(frame);
  const cv::Mat_<float> dense = source->dense_depth();
  CHECK(rgbl::depth_density(dense) > 0.8);
  const std::vector<Eigen::Vector2f> pixels = {{34.0F, 26.0F}};  // samples at columns 2, 6, .., 34 and rows 4, 8, .., 28
  std::vector<rgbl::KeypointDepth> out(1);
  source->sample(pixels, out);
  CHECK(out[0].z == Approx(20.0F).margin(1e-3));
  CHECK(out[0].sample_distance_px == Approx(2.0F));  // (34, 24) and (34, 28)
}

TEST_CASE("lidar source: a scan taken before the image is moved to the image's time (T_image_scan)") {
  // 128x96, f = 100: a wall 10 m ahead above a road 1.5 m below the camera, scanned densely from where
  // the camera was 0.17 m back (17 ms at 10 m/s), by a LiDAR turned as KITTI's (x ahead, z up).
  rgbl::DepthSourceContext context;
  auto& camera = context.calibration.camera;
  camera.fx = camera.fy = 100.0;
  camera.cx = 64.0;
  camera.cy = 48.0;
  camera.width = 128;
  camera.height = 96;
  Eigen::Matrix3d R_cam_lidar;
  R_cam_lidar << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  context.calibration.T_cam_lidar = rgbl::make_isometry(R_cam_lidar, Eigen::Vector3d(0.0, -0.08, -0.27));
  const double wall = 10.0, height = 1.5, moved = 0.17;
  std::vector<rgbl::LidarPoint> scan;
  for (double v = 0.0; v < 96.0; v += 0.5) {
    for (double u = 0.0; u < 128.0; u += 0.5) {
      const Eigen::Vector3d ray((u - 64.0) / 100.0, (v - 48.0) / 100.0, 1.0);
      const double z = ray.y() > 0.0 ? std::min(wall, height / ray.y()) : wall;  // camera at the scan's time
      const Eigen::Vector3d p = context.calibration.T_cam_lidar.inverse() * (z * ray);
      scan.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), 0.0F});
    }
  }
  auto source = rgbl::make_lidar_source(simple_lidar(), context);
  CHECK(source->measured_at_scan_time());
  rgbl::SensorFrame frame;
  frame.scan = scan;
  // the camera drove `moved` ahead: a point at z then is at z - moved now
  frame.T_image_scan = rgbl::make_isometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, -moved));
  source->prepare(frame);
  const std::vector<Eigen::Vector2f> pixels = {{64.0F, 30.0F}, {20.0F, 55.0F}, {64.0F, 80.0F}, {100.0F, 88.0F}};
  std::vector<rgbl::KeypointDepth> out(pixels.size());
  source->sample(pixels, out);
  // what faces the car comes nearer; the road's depth at a pixel does not change as the car drives on
  // (within the z-buffer's half pixel, 0.6 % here; read as a point moved 0.17 m it would be 4.5 % near)
  CHECK_THAT(out[0].z, Catch::Matchers::WithinRel(wall - moved, 0.002));
  CHECK_THAT(out[1].z, Catch::Matchers::WithinRel(wall - moved, 0.002));
  CHECK_THAT(out[2].z, Catch::Matchers::WithinRel(height * 100.0 / 32.0, 0.01));
  CHECK_THAT(out[3].z, Catch::Matchers::WithinRel(height * 100.0 / 40.0, 0.01));
  // taken as simultaneous, the wall is read `moved` too far (1.7 %)
  frame.T_image_scan.setIdentity();
  source->prepare(frame);
  source->sample(pixels, out);
  CHECK_THAT(out[0].z, Catch::Matchers::WithinRel(wall, 0.002));
  CHECK_THAT(out[2].z, Catch::Matchers::WithinRel(height * 100.0 / 32.0, 0.01));
  // depth from a camera of its own is the image's already
  CHECK_FALSE(ConstantSource(1.0F).measured_at_scan_time());
}

TEST_CASE("lidar source: the kernel grows with the rings' spacing in the image, not below 1.5 times its size") {
  // a wall 10 m ahead seen by rings `spacing` px apart (samples every 2 px along each), f = 300 px,
  // 800 x 300 px
  rgbl::DepthSourceContext context;
  context.calibration.camera.fx = context.calibration.camera.fy = 300.0;
  context.calibration.camera.cx = 400.0;
  context.calibration.camera.cy = 150.0;
  context.calibration.camera.width = 800;  // 26 bands of ring_spacing_px, every 31 columns
  context.calibration.camera.height = 300;
  const auto wall = [](int spacing) {
    std::vector<rgbl::LidarPoint> scan;
    for (int v = 10; v < 300; v += spacing) {
      for (int u = 0; u < 800; u += 2) {
        scan.push_back({static_cast<float>((u - 400) * 10.0 / 300.0), static_cast<float>((v - 150) * 10.0 / 300.0),
                        10.0F, 0.0F});
      }
    }
    return scan;
  };
  // depth at a keypoint half-way between two rings (and on a ring, for contrast)
  const auto between = [&](const rgbl::LidarSourceOptions& options, int spacing) {
    auto source = rgbl::make_lidar_source(options, context);
    const std::vector<rgbl::LidarPoint> scan = wall(spacing);
    rgbl::SensorFrame frame;
    frame.scan = scan;  // a view
    source->prepare(frame);
    const std::vector<Eigen::Vector2f> pixels = {{400.0F, 10.0F + 4.0F * spacing + spacing / 2.0F},
                                                 {400.0F, 10.0F + 4.0F * spacing}};
    std::vector<rgbl::KeypointDepth> out(pixels.size());
    source->sample(pixels, out);
    CHECK(out[1].z == Approx(10.0F));
    const cv::Mat_<float> dense = source->dense_depth();
    CHECK(dense(cvRound(pixels[0].y()), 400) == out[0].z);  // the dense map with the same kernel
    return out[0].z;
  };
  rgbl::LidarSourceOptions grows = simple_lidar();
  rgbl::LidarSourceOptions fixed = simple_lidar();
  fixed.kernel_from_ring_spacing = false;
  // 20 px apart (KITTI with a 16-ring LiDAR): the 5x5 diamond leaves the keypoint 10 px from both
  // rings without depth; the grown kernel (21) reaches them
  CHECK(between(fixed, 20) == 0.0F);
  CHECK(between(grows, 20) == Approx(10.0F));
  // 6 px apart (KITTI's HDL-64 is 4-6): the kernel stays 5x5, 3 px is beyond its reach
  CHECK(between(fixed, 6) == 0.0F);
  CHECK(between(grows, 6) == 0.0F);
  // and no further than max_kernel_size: 20 px from both rings 40 px apart, out of a 31x31's reach
  CHECK(between(grows, 40) == 0.0F);
  grows.max_kernel_size = 41;
  CHECK(between(grows, 40) == Approx(10.0F));
  grows.max_kernel_size = 4;
  CHECK_THROWS_WITH(grows.validate(), Contains("lidar.max_kernel_size"));
  // a configured kernel larger than max_kernel_size is kept, not refused
  fixed.dilation.size = 41;
  fixed.kernel_from_ring_spacing = true;
  CHECK(between(fixed, 40) == Approx(10.0F));
}
