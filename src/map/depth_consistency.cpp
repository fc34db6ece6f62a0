#include "rgbl/map/depth_consistency.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace rgbl {

double chi2_95(double dof) {
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + 1.6449 * std::sqrt(a), 3);
}

double depth_consistency_scale(const Map& map, const Landmark& landmark, const PinholeCamera& camera) {
  // the rays' least-squares point: sum P_i (p - c_i) = 0, P_i the projector across ray i over its sigma^2
  int rays = 0, with_depth = 0;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  const double scale_factor = map.options().scale_factor;
  for (const auto& [k, index] : landmark.observations) {
    const Keyframe* kf = map.keyframe(k);
    if (kf == nullptr) continue;
    const Keypoint& kp = kf->keypoints[static_cast<std::size_t>(index)];
    const Eigen::Isometry3d T_world_cam = kf->T_cam_world.inverse();
    const Eigen::Vector3d d = (T_world_cam.linear() * camera.unproject(Eigen::Vector2d(kp.x, kp.y), 1.0)).normalized();
    const Eigen::Vector3d c = T_world_cam.translation();
    // the ray's sideways sigma at the landmark: its level's pixel sigma as an angle, times the distance
    const double sigma = std::pow(scale_factor, kp.level) / camera.fx * (landmark.position - c).norm();
    const Eigen::Matrix3d P = (Eigen::Matrix3d::Identity() - d * d.transpose()) / (sigma * sigma);
    A += P;
    b += P * c;
    ++rays;
    with_depth += kf->depth_sigma[static_cast<std::size_t>(index)] > 0.0F ? 1 : 0;
  }
  if (rays < 3 || with_depth < 2) return 1.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(A);
  const Eigen::Vector3d lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > 1e-9 * lambda(2))) return 1.0;
  const Eigen::Matrix3d covariance = eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  const Eigen::Vector3d p = covariance * b;
  // the test: each depth against the triangulation, by both uncertainties; the factor: the depths' own
  // spread that makes up the excess (what the triangulation's variance does not explain)
  double sum = 0.0, excess = 0.0;
  for (const auto& [k, index] : landmark.observations) {
    const Keyframe* kf = map.keyframe(k);
    if (kf == nullptr) continue;
    const auto i = static_cast<std::size_t>(index);
    const double depth_sigma = kf->depth_sigma[i];
    if (depth_sigma <= 0.0) continue;
    const Eigen::Vector3d axis = kf->T_cam_world.linear().row(2).transpose();  // camera z in the world
    const double variance = axis.dot(covariance * axis);
    const double r = kf->depth[i] - (kf->T_cam_world * p).z();
    sum += r * r / (variance + depth_sigma * depth_sigma);
    excess += (r * r - variance) / (depth_sigma * depth_sigma);
  }
  if (!(sum > chi2_95(with_depth))) return 1.0;  // also a sum that is not a number
  const double scale = std::sqrt(std::max(excess / with_depth, 1.0));
  return std::isfinite(scale) ? scale : 1.0;
}

}  // namespace rgbl
