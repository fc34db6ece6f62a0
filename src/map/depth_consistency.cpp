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
  struct Ray {
    const Keyframe* kf;
    std::size_t index;
    Eigen::Vector3d center, direction;
  };
  std::vector<Ray> rays;
  rays.reserve(landmark.observations.size());
  int with_depth = 0;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  const double scale_factor = map.options().scale_factor;
  for (const auto& [k, index] : landmark.observations) {
    const Keyframe* kf = map.keyframe(k);
    if (kf == nullptr) continue;
    const auto i = static_cast<std::size_t>(index);
    const Eigen::Isometry3d T_world_cam = kf->T_cam_world.inverse();
    const Eigen::Vector3d d =
        (T_world_cam.linear() * camera.unproject(Eigen::Vector2d(kf->keypoints[i].x, kf->keypoints[i].y), 1.0))
            .normalized();
    const Eigen::Vector3d c = T_world_cam.translation();
    // the ray's sideways sigma at the landmark: its level's pixel sigma as an angle, times the distance
    const double sigma = std::pow(scale_factor, kf->keypoints[i].level) / camera.fx * (landmark.position - c).norm();
    const Eigen::Matrix3d P = (Eigen::Matrix3d::Identity() - d * d.transpose()) / (sigma * sigma);
    A += P;
    b += P * c;
    rays.push_back({kf, i, c, d});
    with_depth += kf->depth_sigma[i] > 0.0F ? 1 : 0;
  }
  if (rays.size() < 3 || with_depth < 2) return 1.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(A);
  const Eigen::Vector3d lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > 1e-9 * lambda(2))) return 1.0;
  const Eigen::Matrix3d covariance = eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  const Eigen::Vector3d p = covariance * b;
  // the test: each depth against the triangulation, by both uncertainties; the factor: the depths' own
  // spread that makes up the excess (what the triangulation's variance does not explain)
  double sum = 0.0, excess = 0.0;
  for (const Ray& ray : rays) {
    const double depth_sigma = ray.kf->depth_sigma[ray.index];
    if (depth_sigma <= 0.0) continue;
    const Eigen::Vector3d axis = ray.kf->T_cam_world.linear().row(2).transpose();  // camera z in the world
    const double variance = axis.dot(covariance * axis);
    const double r = ray.kf->depth[ray.index] - (ray.kf->T_cam_world * p).z();
    sum += r * r / (variance + depth_sigma * depth_sigma);
    excess += (r * r - variance) / (depth_sigma * depth_sigma);
  }
  if (!(sum > chi2_95(with_depth))) return 1.0;  // also a sum that is not a number
  const double scale = std::sqrt(std::max(excess / with_depth, 1.0));
  return std::isfinite(scale) ? scale : 1.0;
}

}  // namespace rgbl
