#include "rgbl/core/error.hpp"
#include "rgbl/geometry/camera.hpp"

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
