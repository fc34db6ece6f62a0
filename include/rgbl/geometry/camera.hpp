#pragma once
// Pinhole camera with optional radial-tangential (Brown-Conrady, OpenCV's k1 k2 p1 p2 k3) distortion.
// Pixel coordinates have integer values at pixel centres, as in KITTI's projection matrices and OpenCV.

#include <Eigen/Core>

#include <optional>
#include <string>

namespace rgbl {

struct Distortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;

  bool is_zero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }

  // Normalised image coordinates to distorted ones. A template so that the backend's cost functions
  // differentiate the same formula with Ceres' Jets.
  template <typename T>
  void apply(T& x, T& y) const {
    const T r2 = x * x + y * y;
    const T radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const T xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const T yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    x = xd;
    y = yd;
  }
  // d(distorted) / d(normalised) at (x, y).
  Eigen::Matrix2d jacobian(double x, double y) const;
};

struct PinholeCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  int width = 0, height = 0;
  Distortion distortion{};

  // Throws ConfigError when focal lengths are not positive or the size is empty.
  void validate() const;
  // Why these intrinsics cannot be a real camera's (nullopt when they can): every number finite,
  // focal lengths of 1..1e6 px and, when the size is known (> 0), 0.02..100 times the larger image side
  // (fields of view of 0.6..175 degrees), the principal point within the image widened by its size on
  // each side. Without a size only the absolute bounds apply (|cx|, |cy| <= 1e6).
  std::optional<std::string> implausibility() const;

  Eigen::Matrix3d K() const;

  // Pixel of a point given in this camera's frame; nullopt when it is not in front of the camera
  // (z <= 0) or falls outside the image.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_cam) const;
  // Pixel without visibility checks; z must be non-zero.
  Eigen::Vector2d project_unchecked(const Eigen::Vector3d& p_cam) const;
  // d(project_unchecked) / d(p_cam), lens distortion included; z must be non-zero.
  Eigen::Matrix<double, 2, 3> projection_jacobian(const Eigen::Vector3d& p_cam) const;
  // Point at camera depth z (along the optical axis) seen at pixel px.
  Eigen::Vector3d unproject(const Eigen::Vector2d& px, double z) const;

  // Normalised image coordinates (x/z, y/z) to distorted normalised coordinates, and back.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn) const;
  // Inverse of distort by Gauss-Newton; exact to ~1e-12 within the image for realistic lenses.
  Eigen::Vector2d undistort(const Eigen::Vector2d& xd) const;

  bool in_image(const Eigen::Vector2d& px, double border = 0.0) const {
    return px.x() >= border - 0.5 && px.y() >= border - 0.5 && px.x() < width - 0.5 - border &&
           px.y() < height - 0.5 - border;
  }
};

// The one projection of a point in the camera frame (z != 0) to a pixel: normalised coordinates, the
// lens distortion, the intrinsics. PinholeCamera::project, the tracker and the backend's cost
// functions (T = a Ceres Jet) all use it.
template <typename T>
Eigen::Matrix<T, 2, 1> project_point(const PinholeCamera& camera, const T& x, const T& y, const T& z) {
  T xn = x / z, yn = y / z;
  if (!camera.distortion.is_zero()) camera.distortion.apply(xn, yn);
  return {camera.fx * xn + camera.cx, camera.fy * yn + camera.cy};
}

}  // namespace rgbl
