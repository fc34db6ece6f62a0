#include "bench/reference/dilation_reference.hpp"
#include "bench/reference/occlusion_reference.hpp"
#include "bench/reference/ring_spacing_reference.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/depth/completion.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/projection.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <tuple>
#include <utility>

namespace {

bool bit_identical(const cv::Mat_<float>& a, const cv::Mat_<float>& b) {
  if (a.size() != b.size()) return false;
  for (int y = 0; y < a.rows; ++y) {
    if (std::memcmp(a[y], b[y], sizeof(float) * static_cast<std::size_t>(a.cols)) != 0) return false;
  }
  return true;
}

cv::Mat_<float> reference(const cv::Mat_<float>& sparse, const rgbl::DilationOptions& o) {
  cv::Mat dense;
  rgbl::reference::inverse_dilation(sparse, o.kernel().structuring_element(), o.max_depth, dense);
  return dense;
}

std::vector<rgbl::DilationOptions> all_kernels() {
  std::vector<rgbl::DilationOptions> out;
  for (int size : {3, 5, 7, 9}) out.push_back({rgbl::KernelShape::diamond, size, 200.0F});
  for (int size : {3, 5}) out.push_back({rgbl::KernelShape::rectangle, size, 200.0F});
  for (int size : {3, 5, 7}) out.push_back({rgbl::KernelShape::cross, size, 200.0F});
  return out;
}

cv::Mat_<float> project_frame(const std::filesystem::path& seq, int frame) {
  const auto calib = rgbl::read_kitti_odometry_calibration(seq / "calib.txt", 1226, 370).camera(2);
  const auto scan = rgbl::read_kitti_scan(seq / "velodyne" / fmt::format("{:06d}.bin", frame));
  return rgbl::project_to_depth(scan, calib.P_img_lidar(), 1226, 370);
}

}  // namespace

TEST_CASE("kernels have the documented cells") {
  CHECK(rgbl::Kernel::diamond(5).cell_count() == 13);
  CHECK(rgbl::Kernel::diamond(3).cell_count() == 5);
  CHECK(rgbl::Kernel::diamond(9).cell_count() == 41);
  CHECK(rgbl::Kernel::rectangle(5).cell_count() == 25);
  CHECK(rgbl::Kernel::cross(7).cell_count() == 13);
  const cv::Mat e = rgbl::Kernel::diamond(5).structuring_element();
  const cv::Mat expected = (cv::Mat_<std::uint8_t>(5, 5) << 0, 0, 1, 0, 0, 0, 1, 1, 1, 0, 1, 1, 1, 1, 1, 0, 1, 1, 1,
                            0, 0, 0, 1, 0, 0);
  CHECK(cv::countNonZero(e != expected) == 0);
  CHECK(rgbl::Kernel::cross(3).name() == "cross3");
  CHECK_THROWS_AS(rgbl::Kernel(rgbl::KernelShape::diamond, 4), rgbl::ConfigError);
  CHECK(rgbl::parse_kernel_shape("rectangle") == rgbl::KernelShape::rectangle);
  CHECK_THROWS_WITH(rgbl::parse_kernel_shape("ellipse"), Catch::Contains("diamond, rectangle, cross"));
  rgbl::DilationOptions bad;
  bad.max_depth = 0.0F;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("dilation.max_depth"));
  bad = {};
  bad.size = 6;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("dilation.size"));
}

TEST_CASE("a single point dilates to exactly the 13-cell diamond") {
  cv::Mat_<float> sparse(20, 30, 0.0F);
  sparse(10, 15) = 12.5F;
  const cv::Mat_<float> dense = rgbl::dilate_depth(sparse);
  CHECK(cv::countNonZero(dense) == 13);
  for (int y = 0; y < dense.rows; ++y) {
    for (int x = 0; x < dense.cols; ++x) {
      const bool inside = std::abs(x - 15) + std::abs(y - 10) <= 2;
      INFO("pixel " << x << ", " << y);
      CHECK(dense(y, x) == (inside ? 12.5F : 0.0F));  // 200 - (200 - 12.5) is exact
    }
  }
  // at a corner only the in-image part remains: 6 cells of the diamond
  cv::Mat_<float> corner(20, 30, 0.0F);
  corner(0, 0) = 7.0F;
  CHECK(cv::countNonZero(rgbl::dilate_depth(corner)) == 6);
}

TEST_CASE("the nearer depth wins where kernels overlap") {
  cv::Mat_<float> sparse(10, 10, 0.0F);
  sparse(5, 3) = 30.0F;
  sparse(5, 6) = 10.0F;
  const cv::Mat_<float> dense = rgbl::dilate_depth(sparse);
  CHECK(dense(5, 4) == 10.0F);  // 1 px from the far point, 2 px from the near one
  CHECK(dense(5, 5) == 10.0F);
  CHECK(dense(5, 2) == 30.0F);
  CHECK(dense(5, 1) == 30.0F);
  CHECK(dense(5, 3) == 30.0F);  // the far sample itself is 3 px away from the near one: kept
  CHECK(dense(4, 4) == 30.0F);  // L1 distance 2 to the far point, 3 to the near one
  CHECK(dense(4, 5) == 10.0F);
  // keypoint lookup: value, distance to its source, spread
  const auto k = rgbl::lookup_depth(sparse, {}, Eigen::Vector2f(4.0F, 5.0F));
  CHECK(k.z == 10.0F);
  CHECK(k.sample_distance_px == Approx(2.0F));
  CHECK(k.spread == Approx(20.0F));
  const auto subpixel = rgbl::lookup_depth(sparse, {}, Eigen::Vector2f(5.8F, 5.4F));  // reads cell (6, 5)
  CHECK(subpixel.z == 10.0F);
  CHECK(subpixel.sample_distance_px == Approx(std::hypot(0.2F, 0.4F)));
  CHECK(subpixel.spread == 0.0F);
  CHECK(rgbl::lookup_depth(sparse, {}, Eigen::Vector2f(-3.0F, 5.0F)).z == 0.0F);
  CHECK(rgbl::lookup_depth(sparse, {}, Eigen::Vector2f(0.0F, 0.0F)).z == 0.0F);
}

TEST_CASE("depths the inversion cannot hold count as empty, like the reference") {
  cv::Mat_<float> sparse(8, 8, 0.0F);
  sparse(2, 2) = 250.0F;   // beyond M
  sparse(5, 5) = -3.0F;    // negative
  sparse(6, 1) = 199.99999F;
  sparse(1, 6) = 1e-30F;   // so small that M - d rounds to M: empty for the reference
  sparse(1, 5) = 30.0F;    // ... so this one must win around it
  sparse(7, 7) = 200.0F;   // exactly M
  sparse(0, 7) = std::numeric_limits<float>::infinity();
  for (const auto& o : all_kernels()) CHECK(bit_identical(rgbl::dilate_depth(sparse, o), reference(sparse, o)));
}

TEST_CASE("dilation equals the OpenCV reference bit for bit on random sparse images") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> depth(5.0F, 199.0F);
  std::uniform_real_distribution<float> coin(0.0F, 1.0F);
  for (const float fill : {0.01F, 0.04F, 0.3F, 1.0F}) {
    cv::Mat_<float> sparse(37, 61, 0.0F);
    for (auto& d : sparse) d = coin(rng) < fill ? depth(rng) : 0.0F;
    for (const auto& o : all_kernels()) {
      INFO(o.kernel().name() << " fill " << fill);
      CHECK(bit_identical(rgbl::dilate_depth(sparse, o), reference(sparse, o)));
    }
  }
  // Sizes around the diamond's vector blocks (16 columns, 8 rows per pass, 2 of border) and views into
  // a larger image, whose rows are not contiguous and whose neighbours must not leak in.
  const cv::Mat_<float> big = [&] {
    cv::Mat_<float> m(80, 160, 0.0F);
    for (auto& d : m) d = coin(rng) < 0.1F ? depth(rng) : 0.0F;
    return m;
  }();
  for (const auto& [rows, cols] : {std::pair{1, 1}, {2, 3}, {5, 17}, {9, 19}, {12, 20}, {13, 34}, {17, 35}, {24, 50}, {80, 160}}) {
    for (const bool view : {false, true}) {
      const int x0 = view ? (160 - cols) / 2 : 0, y0 = view ? (80 - rows) / 2 : 0;
      const cv::Mat_<float> sparse = view ? big(cv::Rect(x0, y0, cols, rows)) : cv::Mat_<float>(big(cv::Rect(0, 0, cols, rows)).clone());
      for (const auto& o : all_kernels()) {
        INFO(o.kernel().name() << " " << rows << " x " << cols << (view ? " view" : ""));
        CHECK(bit_identical(rgbl::dilate_depth(sparse, o), reference(sparse, o)));
      }
    }
  }
}

TEST_CASE("dilation equals the reference and keypoint lookup equals the dense map on real frames") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  std::mt19937 rng(3);
  for (const int frame : {0, 25, 50}) {
    const cv::Mat_<float> sparse = project_frame(*seq, frame);
    for (const auto& o : all_kernels()) {
      INFO("frame " << frame << " " << o.kernel().name());
      const cv::Mat_<float> dense = rgbl::dilate_depth(sparse, o);
      REQUIRE(bit_identical(dense, reference(sparse, o)));
      // every pixel of the image, at random sub-pixel offsets within its cell
      std::uniform_real_distribution<float> jitter(-0.49F, 0.49F);
      std::vector<Eigen::Vector2f> pixels;
      for (int y = 0; y < dense.rows; ++y)
        for (int x = 0; x < dense.cols; ++x) pixels.emplace_back(static_cast<float>(x) + jitter(rng), static_cast<float>(y) + jitter(rng));
      std::vector<rgbl::KeypointDepth> depths(pixels.size());
      rgbl::lookup_depth(sparse, o, pixels, depths);
      std::size_t mismatches = 0;
      for (std::size_t i = 0; i < pixels.size(); ++i) {
        const int x = static_cast<int>(i % static_cast<std::size_t>(dense.cols));
        const int y = static_cast<int>(i / static_cast<std::size_t>(dense.cols));
        mismatches += std::memcmp(&depths[i].z, &dense(y, x), sizeof(float)) != 0 ? 1U : 0U;
      }
      CHECK(mismatches == 0);
    }
  }
}

TEST_CASE("density counts pixels with depth") {
  cv::Mat_<float> d(4, 5, 0.0F);
  d(0, 0) = 1.0F;
  d(3, 4) = 2.0F;
  CHECK(rgbl::depth_density(d) == Approx(0.1));
  CHECK(rgbl::depth_density(cv::Mat_<float>()) == 0.0);
}

TEST_CASE("surface-mean keypoint depth removes the minimum's bias on a slanted plane and keeps the foreground") {
  // A road seen by a camera 1.65 m above it (fx = fy = 350, horizon at row 0): inverse depth is affine
  // in the image row, 1/z = v / (350 * 1.65). Every pixel of rows 40-89 holds a sample.
  const double f = 350.0, h = 1.65;
  cv::Mat_<float> sparse(90, 40, 0.0F);
  for (int v = 40; v < 90; ++v) {
    for (int u = 0; u < 40; ++u) sparse(v, u) = static_cast<float>(f * h / v);
  }
  const Eigen::Vector2f pixel(20.0F, 58.0F);
  const double truth = f * h / 58.0;  // 9.96 m
  const rgbl::KeypointDepth dilated = rgbl::lookup_depth(sparse, {}, pixel);
  rgbl::KeypointDepth surface;
  rgbl::lookup_surface_depth(sparse, {}, 0.05F, std::span<const Eigen::Vector2f>(&pixel, 1),
                             std::span<rgbl::KeypointDepth>(&surface, 1));
  // the minimum comes from two rows below: 3.3 % nearer than the road under the keypoint
  CHECK(dilated.z == Approx(f * h / 60.0).epsilon(1e-6));
  CHECK(dilated.z < 0.97 * truth);
  // the diamond is symmetric about the keypoint, so the weighted mean of an affine inverse depth is exact
  CHECK(surface.z == Approx(truth).epsilon(1e-5));
  CHECK(surface.sample_distance_px == 0.0F);
  CHECK(surface.spread == dilated.spread);

  // A foreground post (10 m) in front of a wall (30 m): the wall's samples under the kernel are left
  // out, so the keypoint on the post keeps the post's depth.
  cv::Mat_<float> edge(20, 20, 0.0F);
  for (int v = 0; v < 20; ++v) {
    for (int u = 0; u < 20; ++u) edge(v, u) = u <= 9 ? 10.0F : 30.0F;
  }
  rgbl::KeypointDepth post;
  const Eigen::Vector2f on_edge(10.0F, 10.0F);  // on the wall, one pixel beside the post
  rgbl::lookup_surface_depth(edge, {}, 0.05F, std::span<const Eigen::Vector2f>(&on_edge, 1),
                             std::span<rgbl::KeypointDepth>(&post, 1));
  CHECK(post.z == Approx(10.0F));
  CHECK(post.sample_distance_px == Approx(1.0F));
  CHECK(post.spread == Approx(20.0F));
  rgbl::KeypointDepth outside;
  const Eigen::Vector2f off_image(-3.0F, 5.0F);
  rgbl::lookup_surface_depth(edge, {}, 0.05F, std::span<const Eigen::Vector2f>(&off_image, 1),
                             std::span<rgbl::KeypointDepth>(&outside, 1));
  CHECK(outside.z == 0.0F);
  CHECK_THROWS_AS(rgbl::lookup_surface_depth(edge, {}, 1.5F, std::span<const Eigen::Vector2f>(&on_edge, 1),
                                             std::span<rgbl::KeypointDepth>(&post, 1)),
                  rgbl::ConfigError);
}

TEST_CASE("surface-mean keypoint depth: a ring whose samples lie 3 px apart, with a longer step") {
  // A facade seen at an angle: inverse depth affine in the column, 1/z = 0.05 + 0.0005 (u - 20), the
  // same down every column. One LiDAR ring crosses it on row 50 with a sample every 3 columns (17, 20,
  // 23, ...), as on a 1226 px image. A keypoint 5 rows above the ring under a 21x21 diamond (as grown
  // for rings 21 px apart) reaches the ring's samples at columns 17, 20 and 23.
  cv::Mat_<float> ring(80, 40, 0.0F);
  for (int u = 2; u < 40; u += 3) ring(50, u) = static_cast<float>(1.0 / (0.05 + 0.0005 * (u - 20)));
  const Eigen::Vector2f pixel(20.0F, 45.0F);
  const double truth = 1.0 / 0.05;  // 20 m, the ring's depth straight below
  const rgbl::DilationOptions grown{rgbl::KernelShape::diamond, 21};
  auto depth_with_step = [&](int step_px) {
    rgbl::KeypointDepth out;
    rgbl::lookup_surface_depth(ring, grown, 0.05F, std::span<const Eigen::Vector2f>(&pixel, 1),
                               std::span<rgbl::KeypointDepth>(&out, 1), {}, step_px);
    return out;
  };
  // steps of 2 columns: the surface is the nearest sample alone, the ring's end that faces the camera,
  // 2.9 % short here (on the simulator's facades at 1226 px with 16 rings, 0.5 % in the median)
  const rgbl::KeypointDepth short_step = depth_with_step(2);
  CHECK(short_step.z == Approx(1.0 / (0.05 + 0.0005 * 3)).epsilon(1e-6));
  CHECK(short_step.z < 0.98 * truth);
  // steps of 4: all three join, and the weighted mean of an affine inverse depth, symmetric about the
  // keypoint, is exact
  const rgbl::KeypointDepth long_step = depth_with_step(4);
  CHECK(long_step.z == Approx(truth).epsilon(1e-5));
  CHECK(long_step.sample_distance_px == Approx(5.0F));
  CHECK(long_step.spread == short_step.spread);
  // a depth jump beyond the tolerance still stops the surface (the background behind an edge)
  cv::Mat_<float> edge = ring.clone();
  edge(50, 17) = edge(50, 20) = 40.0F;
  rgbl::KeypointDepth behind;
  rgbl::lookup_surface_depth(edge, grown, 0.05F, std::span<const Eigen::Vector2f>(&pixel, 1),
                             std::span<rgbl::KeypointDepth>(&behind, 1), {}, 4);
  CHECK(behind.z == Approx(1.0 / (0.05 + 0.0005 * 3)).epsilon(1e-6));
  CHECK_THROWS_AS(depth_with_step(0), rgbl::ConfigError);
  CHECK_THROWS_AS(depth_with_step(16), rgbl::ConfigError);
}

TEST_CASE("surface plane fit: a keypoint between two LiDAR rings on the road gets its own depth") {
  // The same road as above (1/z = v / (350 * 1.65)), but sampled only on two rings, rows 50 and 55, as
  // a LiDAR's rings cross it. A keypoint at row 52 has only row 50 under its diamond (radius 2).
  const double f = 350.0, h = 1.65;
  cv::Mat_<float> rings(90, 40, 0.0F);
  for (const int v : {50, 55}) {
    for (int u = 0; u < 40; ++u) rings(v, u) = static_cast<float>(f * h / v);
  }
  const Eigen::Vector2f pixel(20.0F, 52.0F);
  // the camera: fx = fy = 350, the principal point at column 20 on the horizon (row 0)
  rgbl::PinholeCamera camera;
  camera.fx = camera.fy = f;
  camera.cx = 20.0;
  camera.width = 40;
  camera.height = 90;
  auto depth_at = [&](const cv::Mat_<float>& sparse, const Eigen::Vector2f& p, int fit_rows, double max_tilt_deg = 20.0) {
    rgbl::KeypointDepth out;
    rgbl::lookup_surface_depth(sparse, {}, 0.05F, std::span<const Eigen::Vector2f>(&p, 1),
                               std::span<rgbl::KeypointDepth>(&out, 1), {fit_rows, camera, max_tilt_deg});
    return out;
  };
  // without the fit: the ring's depth, 4 % beyond the road under the keypoint
  CHECK(depth_at(rings, pixel, 0).z == Approx(f * h / 50.0).epsilon(1e-6));
  // with rows 49-55 in the window both rings bracket the keypoint: exact, as inverse depth is affine
  const rgbl::KeypointDepth fitted = depth_at(rings, pixel, 3);
  CHECK(fitted.z == Approx(f * h / 52.0).epsilon(1e-5));
  CHECK(fitted.sample_distance_px == Approx(2.0F));  // the kernel's samples, as without the fit
  // and how fast the road's depth changes down the image there: |dz/dv| = f h / v^2 = z^2 / (f h)
  CHECK(fitted.gradient == Approx(f * h / (52.0 * 52.0)).epsilon(1e-4));
  CHECK(depth_at(rings, pixel, 0).gradient == 0.0F);  // the mean does not know it
  // a window that does not reach the second ring leaves the mean as it was (no extrapolation)
  CHECK(depth_at(rings, pixel, 2).z == Approx(f * h / 50.0).epsilon(1e-6));
  // nor does a keypoint beyond both rings: row 56 (only row 55 under its kernel) is not interpolated
  CHECK(depth_at(rings, Eigen::Vector2f(20.0F, 56.0F), 3).z == Approx(f * h / 55.0).epsilon(1e-6));
  // A second surface in the window is not fitted through: the lower ring replaced by a wall twice as
  // far (a depth step beyond the tolerance, however many rows apart), the keypoint keeps its ring's depth.
  cv::Mat_<float> step = rings.clone();
  for (int u = 0; u < 40; ++u) step(55, u) = static_cast<float>(2.0 * f * h / 50.0);
  CHECK(depth_at(step, pixel, 3).z == Approx(f * h / 50.0).epsilon(1e-6));
  CHECK_THROWS_AS(depth_at(rings, pixel, -1), rgbl::ConfigError);

  CHECK_THROWS_AS(depth_at(rings, pixel, 3, 90.0), rgbl::ConfigError);

  // Only a surface about level below the camera is fitted (within 20 deg here). A plane n . X = d in
  // the camera's frame (y down) has 1/z = (n_x (u - 20) / f + n_y v / f + n_z) / d.
  auto plane_rings = [&](const Eigen::Vector3d& n, double d) {  // sampled on rows 50 and 55
    cv::Mat_<float> sparse(90, 40, 0.0F);
    for (const int v : {50, 55}) {
      for (int u = 0; u < 40; ++u) sparse(v, u) = static_cast<float>(d / n.dot(Eigen::Vector3d((u - 20) / f, v / f, 1.0)));
    }
    return sparse;
  };
  auto z_on = [&](const Eigen::Vector3d& n, double d, double v) { return d / n.dot(Eigen::Vector3d(0.0, v / f, 1.0)); };
  const double deg = std::numbers::pi / 180.0;
  // a road falling 10 deg ahead and one sloping 15 deg sideways: fitted exactly
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(0.0, std::cos(10 * deg), std::sin(10 * deg)),
                                  Eigen::Vector3d(std::sin(15 * deg), std::cos(15 * deg), 0.0)}) {
    CAPTURE(n.transpose());
    const rgbl::KeypointDepth on_plane = depth_at(plane_rings(n, h), pixel, 3);
    CHECK(on_plane.z == Approx(z_on(n, h, 52)).epsilon(1e-5));
    // z = h / (n . ray): the gradient is z^2 / (h f) times the normal's part across the image
    const double z = z_on(n, h, 52);
    CHECK(on_plane.gradient == Approx(z * z / (h * f) * std::hypot(n.x(), n.y())).epsilon(1e-4));
  }
  // keeping the ring's depth: a slope falling 30 deg, a wall leaning back 30 deg, a wall at 45 deg to
  // the view
  for (const auto& [n, d] : {std::pair{Eigen::Vector3d(0.0, std::cos(30 * deg), std::sin(30 * deg)), h},
                             std::pair{Eigen::Vector3d(0.0, -std::sin(30 * deg), -std::cos(30 * deg)), -12.0},
                             std::pair{Eigen::Vector3d(std::sqrt(0.5), 0.0, std::sqrt(0.5)), 10.0}}) {
    CAPTURE(n.transpose(), d);
    const cv::Mat_<float> sparse = plane_rings(n, d);
    REQUIRE(sparse(50, 20) > 0.0F);
    REQUIRE(sparse(55, 20) > 0.0F);
    CHECK(depth_at(sparse, pixel, 3).z == Approx(z_on(n, d, 50)).epsilon(1e-6));
  }

  // Nor across a depth step: a keypoint at row 50 on an object 50 m away (rows 51 and 53) with another
  // at 54 m above it (rows 47 and 49). 8 % is too much for rows 2 apart, but the fit's growth allows
  // 10 % between rows 4 apart (53 to 49), so the window holds both; fitted, their plane would say
  // 51.9 m. Their scatter about it is far beyond pixel rounding and 2 cm of range noise, so the object
  // keeps its 50 m, even with the tilt test all but off (89 deg).
  cv::Mat_<float> step_up(90, 40, 0.0F);
  for (int u = 0; u < 40; ++u) {
    for (const int v : {47, 49}) step_up(v, u) = 54.0F;
    for (const int v : {51, 53}) step_up(v, u) = 50.0F;
  }
  const Eigen::Vector2f at_50(20.0F, 50.0F);
  CHECK(depth_at(step_up, at_50, 3, 89.0).z == Approx(50.0));
  // the same rows on one plane (inverse depth affine in the row) are fitted
  cv::Mat_<float> ramp(90, 40, 0.0F);
  for (int u = 0; u < 40; ++u) {
    for (const int v : {47, 49, 51, 53}) ramp(v, u) = static_cast<float>(1.0 / (1.0 / 50.0 + (v - 51) * 1e-4));
  }
  CHECK(depth_at(ramp, at_50, 3, 89.0).z == Approx(1.0 / (1.0 / 50.0 - 1e-4)).epsilon(1e-5));
}

TEST_CASE("samples behind a foreground edge in the camera's view are dropped, a slanted road is kept") {
  // A post at 10 m in columns 20-22 in front of a wall at 30 m; one wall return has landed on the
  // post itself (what a LiDAR behind the camera sees past the edge).
  cv::Mat_<float> sparse(40, 60, 0.0F);
  for (int v = 0; v < 40; v += 2) {
    for (int u = 0; u < 60; u += 2) sparse(v, u) = (u >= 20 && u <= 22) ? 10.0F : 30.0F;
  }
  sparse(10, 21) = 30.0F;
  const cv::Mat_<float> before = sparse.clone();
  const int dropped = rgbl::remove_occluded_samples(sparse, 4, 1.25F);
  int expected = 0;
  for (int v = 0; v < 40; ++v) {
    for (int u = 0; u < 60; ++u) {
      if (before(v, u) <= 0.0F) continue;
      // a wall sample within 4 px (a square) of a post sample goes; everything else stays
      const bool behind = before(v, u) == 30.0F && ((u >= 16 && u <= 26) || (v == 10 && u == 21));
      expected += behind ? 1 : 0;
      INFO("pixel " << u << ", " << v);
      CHECK(sparse(v, u) == (behind ? 0.0F : before(v, u)));
    }
  }
  CHECK(dropped == expected);
  CHECK(sparse(10, 21) == 0.0F);

  // The road (fx = 350, 1.65 m up, horizon at row 0) changes its depth by 13 % over 4 rows at row 30
  // (16 m): under the 25 %, nothing goes. Off (radius 0) changes nothing either.
  cv::Mat_<float> road(90, 40, 0.0F);
  for (int v = 30; v < 90; ++v) {
    for (int u = 0; u < 40; ++u) road(v, u) = static_cast<float>(350.0 * 1.65 / v);
  }
  CHECK(rgbl::remove_occluded_samples(road, 4, 1.25F) == 0);
  CHECK(rgbl::remove_occluded_samples(sparse, 0, 1.25F) == 0);
  CHECK_THROWS_AS(rgbl::remove_occluded_samples(road, 4, 1.0F), rgbl::ConfigError);
}

TEST_CASE("the occlusion filter equals the straightforward window scan, with one scratch image reused") {
  // Random sparse images of several sizes, samples only in a band of rows (as a scan's) or touching
  // the borders, depths spread over 2-60 m so that many samples have a nearer one within the window.
  std::mt19937 rng(5);
  cv::Mat_<float> scratch;
  for (const auto& [rows, cols, top, bottom, radius] :
       {std::tuple{40, 60, 10, 30, 4}, std::tuple{37, 53, 0, 37, 2}, std::tuple{90, 120, 50, 90, 6},
        std::tuple{20, 20, 5, 6, 4}, std::tuple{30, 41, 0, 3, 1}}) {
    cv::Mat_<float> sparse(rows, cols, 0.0F);
    std::uniform_real_distribution<float> depth(2.0F, 60.0F);
    std::bernoulli_distribution sample(0.2);
    for (int v = top; v < bottom; ++v) {
      for (int u = 0; u < cols; ++u) sparse(v, u) = sample(rng) ? depth(rng) : 0.0F;
    }
    cv::Mat_<float> expected = sparse.clone();
    const int expected_dropped = rgbl::reference::remove_occluded_samples(expected, radius, 1.25F);
    const int dropped = rgbl::remove_occluded_samples(sparse, radius, 1.25F, scratch);
    INFO(rows << " x " << cols << ", rows " << top << "-" << bottom << ", radius " << radius);
    CHECK(expected_dropped > 0);
    CHECK(dropped == expected_dropped);
    CHECK(cv::countNonZero(sparse != expected) == 0);
  }
  cv::Mat_<float> empty(10, 10, 0.0F);
  CHECK(rgbl::remove_occluded_samples(empty, 4, 1.25F, scratch) == 0);
}

TEST_CASE("ring spacing: the median gap between a scan's rings in the image") {
  // rings as rows of samples every `spacing` px, each ring's samples 2 px apart along it (so one column
  // alone misses a ring half the time; on KITTI they lie 3 px apart within an image row), offset by one
  // column from ring to ring
  const auto rings = [](int spacing, int first_row = 3) {
    cv::Mat_<float> sparse(300, 400, 0.0F);
    for (int r = first_row, k = 0; r < sparse.rows; r += spacing, ++k) {
      for (int c = k % 2; c < sparse.cols; c += 2) sparse(r, c) = 10.0F;
    }
    return sparse;
  };
  CHECK(rgbl::ring_spacing_px(rings(5)) == Approx(5.0));
  CHECK(rgbl::ring_spacing_px(rings(10)) == Approx(10.0));
  CHECK(rgbl::ring_spacing_px(rings(20)) == Approx(20.0));
  // a ring that left no return in a band (sky, a dark car) makes one gap twice as long: not the median
  cv::Mat_<float> holes = rings(10);
  for (int c = 0; c < holes.cols; c += 96) holes.row(93).colRange(c, c + 3).setTo(0.0F);
  CHECK(rgbl::ring_spacing_px(holes) == Approx(10.0));
  // samples of one ring on neighbouring rows (a ring's curve in the image) are not a gap
  cv::Mat_<float> curved = rings(10);
  for (int c = 0; c < curved.cols; c += 2) curved(4, c) = 10.0F;
  CHECK(rgbl::ring_spacing_px(curved) == Approx(10.0));
  // too few gaps to tell: no spacing
  CHECK_FALSE(rgbl::ring_spacing_px(cv::Mat_<float>(300, 400, 0.0F)).has_value());
  cv::Mat_<float> two(300, 400, 0.0F);
  two.row(10).setTo(5.0F);
  two.row(30).setTo(5.0F);
  CHECK_FALSE(rgbl::ring_spacing_px(two).has_value());  // 27 bands (a stride of 15), one gap each
  CHECK(rgbl::ring_spacing_px(two, 27) == Approx(20.0));
  CHECK_FALSE(rgbl::ring_spacing_px(two, 28).has_value());
  // a narrow image keeps its 26 bands: 16 rings 10 px apart over 160 rows of a 613 px image give 26 x 15
  // gaps; at one band every 48 columns (13 bands) they were 195, too few for the default 100 only after
  // the occlusion filter thinned them, so here the count itself is checked
  cv::Mat_<float> narrow(370, 613, 0.0F);
  for (int r = 200; r < 360; r += 10) narrow.row(r).setTo(8.0F);
  CHECK(rgbl::ring_spacing_px(narrow, 26 * 15) == Approx(10.0));
  CHECK_FALSE(rgbl::ring_spacing_px(narrow, 26 * 15 + 1).has_value());
}

TEST_CASE("ring spacing on a real scan: the sampled bands agree with every band") {
  const auto seq = rgbl::test::kitti_seq04();
  if (!seq) return;
  const auto kitti = rgbl::read_kitti_odometry_calibration(*seq / "calib.txt", 1226, 370);
  const auto camera = kitti.camera(0);
  for (const int frame : {0, 25, 50}) {
    const auto scan = rgbl::read_kitti_scan(*seq / "velodyne" / fmt::format("{:06d}.bin", frame));
    const cv::Mat_<float> sparse =
        rgbl::project_to_depth(scan, camera.P_img_lidar(), camera.camera.width, camera.camera.height);
    INFO("frame " << frame);
    const auto spacing = rgbl::ring_spacing_px(sparse);
    REQUIRE(spacing.has_value());
    CHECK(*spacing == rgbl::reference::ring_spacing_px(sparse));
    CHECK(*spacing == Approx(5.0));  // the HDL-64 on KITTI: its 5x5 diamond's own case
  }
}
