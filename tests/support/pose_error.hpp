#pragma once
// How far an estimated relative pose between two frames is from the truth's: what the loop tests ask
// of a closure (a true one agrees with the truth however far apart its frames are; a false one ties
// two places together).

#include "rgbl/geometry/se3.hpp"

#include <Eigen/Geometry>

#include <numbers>
#include <utility>

namespace rgbl::test {

// (m, deg) of E = (T_truth_a^-1 T_truth_b)^-1 (T_estimate_a^-1 T_estimate_b), T_world_cam poses.
inline std::pair<double, double> relative_error(const Eigen::Isometry3d& truth_a, const Eigen::Isometry3d& truth_b,
                                                const Eigen::Isometry3d& estimate_a,
                                                const Eigen::Isometry3d& estimate_b) {
  const Eigen::Isometry3d E = (truth_a.inverse() * truth_b).inverse() * (estimate_a.inverse() * estimate_b);
  return {E.translation().norm(), rotation_angle(E.linear()) * 180.0 / std::numbers::pi};
}

}  // namespace rgbl::test
