#pragma once
// Pinhole camera with optional radial-tangential (Brown-Conrady, OpenCV's k1 k2 p1 p2 k3) distortion.
// Pixel coordinates have integer values at pixel centres, as in KITTI's projection matrices and OpenCV.

#include <Eigen/Core>

#include <optional>

namespace rgbl {

struct Distortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;

  bool is_zero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
};

struct PinholeCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  int width = 0, height = 0;
  Distortion distortion{};

  // Throws ConfigError when focal lengths are not positive or the size is empty.
  void validate() const;

  Eigen::Matrix3d K() const;

  // Pixel of a point given in this camera's frame; nullopt when it is not in front of the camera
  // (z <= 0) or falls outside the image.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_cam) const;
  // Pixel without visibility checks; z must be non-zero.
  Eigen::Vector2d project_unchecked(const Eigen::Vector3d& p_cam) const;
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

}  // namespace rgbl
