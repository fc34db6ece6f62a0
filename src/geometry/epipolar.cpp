#include "rgbl/geometry/epipolar.hpp"

#include <algorithm>

namespace rgbl {

bool clip_segment(Eigen::Vector2d& a, Eigen::Vector2d& b, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector2d d = b - a;
  for (int axis = 0; axis < 2; ++axis) {
    for (const auto& [p, q] : {std::pair{-d(axis), a(axis) - lo(axis)}, std::pair{d(axis), hi(axis) - a(axis)}}) {
      if (p == 0.0) {
        if (q < 0.0) return false;
        continue;
      }
      const double r = q / p;
      if (p < 0.0) t0 = std::max(t0, r);
      else t1 = std::min(t1, r);
    }
  }
  if (t0 > t1) return false;
  const Eigen::Vector2d start = a + t0 * d;
  b = a + t1 * d;
  a = start;
  return true;
}

std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> epipolar_segment(const Eigen::Isometry3d& T_other_own,
                                                                           const Eigen::Vector3d& ray, double min_depth,
                                                                           const PinholeCamera& camera, double margin) {
  // the point at inverse depth rho, up to scale: R ray + t rho; in front where its z > 0
  const Eigen::Vector3d far = T_other_own.linear() * ray, t = T_other_own.translation();
  constexpr double kFront = 1e-3;
  double rho_lo = 0.0, rho_hi = 1.0 / min_depth;
  const auto z = [&](double rho) { return far.z() + t.z() * rho; };
  if (z(rho_lo) <= kFront && z(rho_hi) <= kFront) return std::nullopt;
  if (z(rho_lo) <= kFront) rho_lo = (kFront - far.z()) / t.z();
  if (z(rho_hi) <= kFront) rho_hi = (kFront - far.z()) / t.z();
  Eigen::Vector2d a = camera.project_unchecked(far + t * rho_lo), b = camera.project_unchecked(far + t * rho_hi);
  if (!clip_segment(a, b, Eigen::Vector2d(-margin, -margin), Eigen::Vector2d(camera.width + margin, camera.height + margin)))
    return std::nullopt;
  return std::pair{a, b};
}

double distance_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double s = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + s * ab - p).norm();
}

}  // namespace rgbl
