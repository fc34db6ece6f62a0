#include "rgbl/geometry/camera.hpp"

#include "rgbl/core/error.hpp"

#include <Eigen/LU>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace rgbl {

void PinholeCamera::validate() const {
  require(fx > 0.0 && fy > 0.0, "camera.fx/fy", "focal lengths > 0");
  require(width > 0 && height > 0, "camera.width/height", "an image size > 0");
}

std::optional<std::string> PinholeCamera::implausibility() const {
  const double values[] = {fx, fy, cx, cy, distortion.k1, distortion.k2, distortion.p1, distortion.p2, distortion.k3};
  for (const double v : values) {
    if (!std::isfinite(v)) return "intrinsics and distortion must be finite numbers";
  }
  const auto focal = [](double f) { return fmt::format("{:g}", f); };
  if (!(fx >= 1.0 && fx <= 1e6 && fy >= 1.0 && fy <= 1e6)) {
    return fmt::format("focal lengths fx {} fy {} px are outside 1..1e6 px", focal(fx), focal(fy));
  }
  if (!(std::abs(cx) <= 1e6 && std::abs(cy) <= 1e6)) {
    return fmt::format("principal point ({:g}, {:g}) px is outside +-1e6 px", cx, cy);
  }
  if (width <= 0 || height <= 0) return std::nullopt;
  const double side = std::max(width, height);
  if (!(fx >= 0.02 * side && fx <= 100.0 * side && fy >= 0.02 * side && fy <= 100.0 * side)) {
    return fmt::format("focal lengths fx {} fy {} px are implausible for a {}x{} image (expected 0.02..100 times "
                       "its larger side: fields of view of 0.6..175 degrees)",
                       focal(fx), focal(fy), width, height);
  }
  if (!(cx >= -width && cx <= 2.0 * width && cy >= -height && cy <= 2.0 * height)) {
    return fmt::format("principal point ({:g}, {:g}) px is far outside the {}x{} image", cx, cy, width, height);
  }
  return std::nullopt;
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

Eigen::Vector2d PinholeCamera::project_unchecked(const Eigen::Vector3d& p_cam) const {
  return project_point(*this, p_cam.x(), p_cam.y(), p_cam.z());
}

Eigen::Matrix<double, 2, 3> PinholeCamera::projection_jacobian(const Eigen::Vector3d& p_cam) const {
  // fx, fy times d(distorted) / d(normalised) times d(normalised) / d(p)
  const double iz = 1.0 / p_cam.z();
  Eigen::Matrix<double, 2, 3> dnormalised;
  dnormalised << iz, 0.0, -p_cam.x() * iz * iz,  //
      0.0, iz, -p_cam.y() * iz * iz;
  if (!distortion.is_zero()) dnormalised = distortion.jacobian(p_cam.x() * iz, p_cam.y() * iz) * dnormalised;
  return Eigen::Vector2d(fx, fy).asDiagonal() * dnormalised;
}

std::optional<Eigen::Vector2d> PinholeCamera::project(const Eigen::Vector3d& p_cam) const {
  if (!(p_cam.z() > 0.0)) return std::nullopt;
  const Eigen::Vector2d px = project_unchecked(p_cam);
  if (!in_image(px)) return std::nullopt;
  return px;
}

Eigen::Vector3d PinholeCamera::unproject(const Eigen::Vector2d& px, double z) const {
  Eigen::Vector2d xn((px.x() - cx) / fx, (px.y() - cy) / fy);
  if (!distortion.is_zero()) xn = undistort(xn);
  return {xn.x() * z, xn.y() * z, z};
}

Eigen::Vector2d PinholeCamera::distort(const Eigen::Vector2d& xn) const {
  double x = xn.x(), y = xn.y();
  distortion.apply(x, y);
  return {x, y};
}

Eigen::Matrix2d Distortion::jacobian(double u, double v) const {
  const double r2 = u * u + v * v;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double dradial_dr2 = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);
  Eigen::Matrix2d J;
  J(0, 0) = radial + 2.0 * u * u * dradial_dr2 + 2.0 * p1 * v + 6.0 * p2 * u;
  J(0, 1) = 2.0 * u * v * dradial_dr2 + 2.0 * p1 * u + 2.0 * p2 * v;
  J(1, 0) = J(0, 1);
  J(1, 1) = radial + 2.0 * v * v * dradial_dr2 + 6.0 * p1 * v + 2.0 * p2 * u;
  return J;
}

Eigen::Vector2d PinholeCamera::undistort(const Eigen::Vector2d& xd) const {
  const auto& d = distortion;
  Eigen::Vector2d x = xd;  // distortion is a small perturbation: the distorted point is a good start
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Eigen::Vector2d residual = distort(x) - xd;
    if (residual.squaredNorm() < 1e-26) break;
    x -= d.jacobian(x.x(), x.y()).inverse() * residual;
  }
  return x;
}

}  // namespace rgbl
