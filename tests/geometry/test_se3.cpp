#include "rgbl/geometry/se3.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

using Catch::Matchers::WithinAbs;

namespace {
rgbl::Vector6d random_twist(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> dist(-scale, scale);
  rgbl::Vector6d xi;
  for (int i = 0; i < 6; ++i) xi(i) = dist(rng);
  return xi;
}
}  // namespace

TEST_CASE("hat is the cross product matrix") {
  const Eigen::Vector3d a(1.0, -2.0, 0.5), b(0.3, 0.7, -1.1);
  CHECK((rgbl::hat(a) * b - a.cross(b)).norm() < 1e-15);
}

TEST_CASE("se3 exp and log are inverse to each other") {
  std::mt19937 rng(7);
  for (int i = 0; i < 200; ++i) {
    const rgbl::Vector6d xi = random_twist(rng, 1.5);
    const Eigen::Isometry3d T = rgbl::se3_exp(xi);
    CHECK((T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
    CHECK((rgbl::se3_log(T) - xi).norm() < 1e-9);
  }
  // tiny twists take the Taylor branches
  rgbl::Vector6d tiny;
  tiny << 1e-9, -2e-9, 3e-9, 1e-11, -4e-11, 2e-11;
  CHECK((rgbl::se3_log(rgbl::se3_exp(tiny)) - tiny).norm() < 1e-18);
}

TEST_CASE("so3 log is stable near pi") {
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, -0.5).normalized();
  for (double angle : {M_PI - 1e-9, M_PI - 1e-5, M_PI}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const Eigen::Vector3d phi = rgbl::so3_log(R);
    CHECK_THAT(phi.norm(), WithinAbs(angle, 1e-7));
    CHECK((rgbl::so3_exp(phi) - R).norm() < 1e-9);
  }
  CHECK_THAT(rgbl::rotation_angle(Eigen::AngleAxisd(1e-8, axis).toRotationMatrix()), WithinAbs(1e-8, 1e-15));
}

TEST_CASE("se3 exp of a pure translation and a known rotation") {
  rgbl::Vector6d xi = rgbl::Vector6d::Zero();
  xi.head<3>() << 1.0, 2.0, 3.0;
  CHECK((rgbl::se3_exp(xi).translation() - Eigen::Vector3d(1.0, 2.0, 3.0)).norm() < 1e-15);
  // rotation of pi/2 about z with rho along x moves along the arc: t = V * rho = (2/pi, 2/pi, 0)
  xi << 1.0, 0.0, 0.0, 0.0, 0.0, M_PI / 2.0;
  const Eigen::Isometry3d T = rgbl::se3_exp(xi);
  CHECK((T.translation() - Eigen::Vector3d(2.0 / M_PI, 2.0 / M_PI, 0.0)).norm() < 1e-12);
}

TEST_CASE("interpolation hits the end points and the geodesic midpoint") {
  std::mt19937 rng(11);
  const Eigen::Isometry3d T_a = rgbl::se3_exp(random_twist(rng, 1.0));
  const Eigen::Isometry3d T_b = rgbl::se3_exp(random_twist(rng, 1.0));
  CHECK((rgbl::interpolate(T_a, T_b, 0.0).matrix() - T_a.matrix()).norm() < 1e-12);
  CHECK((rgbl::interpolate(T_a, T_b, 1.0).matrix() - T_b.matrix()).norm() < 1e-9);
  const Eigen::Isometry3d mid = rgbl::interpolate(T_a, T_b, 0.5);
  // the midpoint is equally far (in the tangent space) from both ends
  const double d_a = rgbl::se3_log(T_a.inverse() * mid).norm();
  const double d_b = rgbl::se3_log(mid.inverse() * T_b).norm();
  CHECK_THAT(d_a, WithinAbs(d_b, 1e-9));
}

TEST_CASE("3x4 conversions round trip") {
  std::mt19937 rng(3);
  const Eigen::Isometry3d T = rgbl::se3_exp(random_twist(rng, 2.0));
  CHECK((rgbl::isometry_from_3x4(rgbl::to_3x4(T)).matrix() - T.matrix()).norm() < 1e-15);
}

TEST_CASE("a pose placed by its camera centre keeps the rotation and has that centre") {
  std::mt19937 rng(5);
  const Eigen::Isometry3d T = rgbl::se3_exp(random_twist(rng, 2.0));
  const Eigen::Vector3d centre(1.0, -2.0, 30.0);
  const Eigen::Isometry3d placed = rgbl::pose_at_centre(T.linear(), centre);
  CHECK((placed.linear() - T.linear()).norm() == 0.0);
  CHECK((placed.inverse().translation() - centre).norm() < 1e-12);
  CHECK((placed * centre).norm() < 1e-12);  // the centre is the camera's origin
}
