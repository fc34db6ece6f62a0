#pragma once
// Rigid-body transforms on Eigen. A transform is named by its frames: T_a_b maps points expressed in
// frame b into frame a (p_a = T_a_b * p_b), so T_a_c = T_a_b * T_b_c.
// Tangent vectors are ordered [rho (translation part); phi (rotation part)].

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rgbl {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix34d = Eigen::Matrix<double, 3, 4>;

// Skew-symmetric matrix with hat(a) * b == a.cross(b).
Eigen::Matrix3d hat(const Eigen::Vector3d& v);

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& phi);
// Left Jacobian of SO(3): so3_exp(phi + d) ~ so3_exp(so3_left_jacobian(phi) * d) * so3_exp(phi); and its
// inverse. Taylor expansions near phi = 0.
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& phi);
Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& phi);
// Rotation vector of R, angle in [0, pi]; stable near 0 and pi.
Eigen::Vector3d so3_log(const Eigen::Matrix3d& R);

Eigen::Isometry3d se3_exp(const Vector6d& xi);
Vector6d se3_log(const Eigen::Isometry3d& T);

// Geodesic interpolation: s = 0 gives T_a, s = 1 gives T_b.
Eigen::Isometry3d interpolate(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b, double s);

// Angle of a rotation in radians, in [0, pi].
double rotation_angle(const Eigen::Matrix3d& R);

// How far R is from a rotation: the larger of max|R^T R - I| and |det R - 1|; NaN for non-finite R.
// Rotations printed with 7 significant digits (KITTI's calibration files) are off by ~1e-7.
double rotation_error(const Eigen::Matrix3d& R);

Eigen::Isometry3d make_isometry(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
// The pose T_cam_world with rotation R_cam_world whose camera centre is `centre` (world): t = -R c.
Eigen::Isometry3d pose_at_centre(const Eigen::Matrix3d& R_cam_world, const Eigen::Vector3d& centre);
// T with its rotation replaced by the nearest rotation (to first order; through the unit quaternion).
// Isometry3d::inverse() transposes: a pose off by 1e-7 (conjugated with KITTI's printed extrinsics)
// and then composed with its own inverse, frame after frame, drifts off geometrically.
Eigen::Isometry3d orthonormalized(const Eigen::Isometry3d& T);
Eigen::Isometry3d isometry_from_3x4(const Matrix34d& M);
Matrix34d to_3x4(const Eigen::Isometry3d& T);

}  // namespace rgbl
