#include "rgbl/geometry/se3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rgbl {

// Left Jacobian of SO(3) and its inverse, with Taylor expansions where the closed forms lose
// precision (theta^2 below ~1e-10 makes the 1/theta^2 terms cancel catastrophically).
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const Eigen::Matrix3d K = hat(phi);
  if (theta2 < 1e-10) return Eigen::Matrix3d::Identity() + 0.5 * K + K * K / 6.0;
  const double theta = std::sqrt(theta2);
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / theta2 * K +
         (theta - std::sin(theta)) / (theta2 * theta) * K * K;
}

Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const Eigen::Matrix3d K = hat(phi);
  if (theta2 < 1e-10) return Eigen::Matrix3d::Identity() - 0.5 * K + K * K / 12.0;
  const double theta = std::sqrt(theta2);
  const double c = (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) / theta2;
  return Eigen::Matrix3d::Identity() - 0.5 * K + c * K * K;
}

Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  if (theta < 1e-12) return Eigen::Matrix3d::Identity() + hat(phi);
  return Eigen::AngleAxisd(theta, phi / theta).toRotationMatrix();
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d& R) {
  // Through the unit quaternion: atan2 keeps full precision near 0 and near pi.
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  if (n < 1e-12) return 2.0 * q.vec() / q.w();
  const double angle = 2.0 * std::atan2(n, q.w());
  return angle / n * q.vec();
}

Eigen::Isometry3d se3_exp(const Vector6d& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.tail<3>();
  return make_isometry(so3_exp(phi), so3_left_jacobian(phi) * rho);
}

Vector6d se3_log(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d phi = so3_log(T.linear());
  Vector6d xi;
  xi.head<3>() = so3_left_jacobian_inverse(phi) * T.translation();
  xi.tail<3>() = phi;
  return xi;
}

Eigen::Isometry3d interpolate(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b, double s) {
  return T_a * se3_exp(s * se3_log(T_a.inverse() * T_b));
}

double rotation_angle(const Eigen::Matrix3d& R) {
  // acos of the trace is imprecise near 0; the quaternion route is not.
  return so3_log(R).norm();
}

double rotation_error(const Eigen::Matrix3d& R) {
  if (!R.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  return std::max((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
                  std::abs(R.determinant() - 1.0));
}

Eigen::Isometry3d make_isometry(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Isometry3d pose_at_centre(const Eigen::Matrix3d& R_cam_world, const Eigen::Vector3d& centre) {
  return make_isometry(R_cam_world, -(R_cam_world * centre));
}

Eigen::Isometry3d orthonormalized(const Eigen::Isometry3d& T) {
  return make_isometry(Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix(), T.translation());
}

Eigen::Isometry3d isometry_from_3x4(const Matrix34d& M) {
  return make_isometry(M.leftCols<3>(), M.col(3));
}

Matrix34d to_3x4(const Eigen::Isometry3d& T) { return T.matrix().topRows<3>(); }

}  // namespace rgbl
