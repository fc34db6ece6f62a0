#include "rgbl/core/error.hpp"
#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/epipolar.hpp"

#include <catch2/catch.hpp>

#include <random>

namespace {
rgbl::PinholeCamera kitti_like() {
  rgbl::PinholeCamera cam;
  cam.fx = 707.0912;
  cam.fy = 707.0912;
  cam.cx = 601.8873;
  cam.cy = 183.1104;
  cam.width = 1226;
  cam.height = 370;
  return cam;
}
}  // namespace

TEST_CASE("project and unproject round trip") {
  const rgbl::PinholeCamera cam = kitti_like();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, cam.width - 1.0), v(0.0, cam.height - 1.0), z(0.5, 120.0);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector2d px(u(rng), v(rng));
    const Eigen::Vector3d p = cam.unproject(px, z(rng));
    const auto back = cam.project(p);
    REQUIRE(back.has_value());
    CHECK((*back - px).norm() < 1e-9);
  }
}

TEST_CASE("project rejects points behind the camera and outside the image") {
  const rgbl::PinholeCamera cam = kitti_like();
  CHECK_FALSE(cam.project({0.0, 0.0, -1.0}).has_value());
  CHECK_FALSE(cam.project({0.0, 0.0, 0.0}).has_value());
  CHECK_FALSE(cam.project({100.0, 0.0, 1.0}).has_value());
  const auto centre = cam.project({0.0, 0.0, 10.0});
  REQUIRE(centre.has_value());
  CHECK((*centre - Eigen::Vector2d(cam.cx, cam.cy)).norm() < 1e-12);
}

TEST_CASE("undistort inverts distort for a strong real lens") {
  // KITTI raw 2011_09_26 camera 00 (unrectified): k1 = -0.37, a strongly barrel-distorted lens.
  rgbl::PinholeCamera cam;
  cam.fx = 984.2439;
  cam.fy = 980.8141;
  cam.cx = 690.0;
  cam.cy = 233.1966;
  cam.width = 1392;
  cam.height = 512;
  cam.distortion = {-3.728755e-01, 2.037299e-01, 2.219027e-03, 1.383707e-03, -7.233722e-02};
  double worst = 0.0;
  for (int v = 0; v < cam.height; v += 16) {
    for (int u = 0; u < cam.width; u += 16) {
      const Eigen::Vector2d xd((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy);
      const Eigen::Vector2d xn = cam.undistort(xd);
      worst = std::max(worst, (cam.distort(xn) - xd).norm());
    }
  }
  CHECK(worst < 1e-10);
  // and project(unproject(px)) returns the pixel through the distortion model
  const Eigen::Vector2d px(1300.0, 40.0);
  const auto back = cam.project(cam.unproject(px, 7.0));
  REQUIRE(back.has_value());
  CHECK((*back - px).norm() < 1e-6);
}

TEST_CASE("camera validation names the bad option") {
  rgbl::PinholeCamera cam = kitti_like();
  CHECK_NOTHROW(cam.validate());
  cam.fx = 0.0;
  CHECK_THROWS_AS(cam.validate(), rgbl::ConfigError);
}

TEST_CASE("epipolar segment: a ray from its nearest depth to infinity, clipped to the widened image", "[geometry]") {
  const rgbl::PinholeCamera cam = kitti_like();
  const Eigen::Vector3d ray(0.2, 0.0, 1.0);  // z = 1: the point at depth d is d * ray
  // driving 1 m forward: the far end stays on the ray's pixel, the nearest point (4 m, now 3 m ahead) moves out
  Eigen::Isometry3d T_forward = Eigen::Isometry3d::Identity();
  T_forward.translation() = Eigen::Vector3d(0.0, 0.0, -1.0);
  const auto s = rgbl::epipolar_segment(T_forward, ray, 4.0, cam, 2.0);
  REQUIRE(s);
  CHECK(s->first.x() == Approx(cam.cx + cam.fx * 0.2));
  CHECK(s->second.x() == Approx(cam.cx + cam.fx * 0.8 / 3.0));  // 4 m * 0.2 sideways, 3 m ahead
  CHECK(s->first.y() == Approx(cam.cy));
  // from a nearest depth of 1.2 m: that point would be 0.2 m ahead at 0.24 m sideways (x = cx +
  // 1.2 fx, beyond the image), so the segment is clipped at the image's edge plus the margin
  const auto clipped = rgbl::epipolar_segment(T_forward, ray, 1.2, cam, 2.0);
  REQUIRE(clipped);
  CHECK(clipped->second.x() == Approx(cam.width + 2.0));
  // a ray that ends behind the camera: nothing of it in view
  Eigen::Isometry3d T_turned = Eigen::Isometry3d::Identity();
  T_turned.linear() = Eigen::AngleAxisd(3.14159265358979, Eigen::Vector3d::UnitY()).toRotationMatrix();
  CHECK_FALSE(rgbl::epipolar_segment(T_turned, ray, 4.0, cam, 2.0));
  // distances to a segment: across it, beyond an end, to a point-segment
  const Eigen::Vector2d a(0.0, 0.0), b(10.0, 0.0);
  CHECK(rgbl::distance_to_segment(Eigen::Vector2d(5.0, 3.0), a, b) == Approx(3.0));
  CHECK(rgbl::distance_to_segment(Eigen::Vector2d(13.0, 4.0), a, b) == Approx(5.0));
  CHECK(rgbl::distance_to_segment(Eigen::Vector2d(3.0, 4.0), a, a) == Approx(5.0));
}
