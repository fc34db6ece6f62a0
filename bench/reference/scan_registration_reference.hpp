#pragma once
// Point-to-plane ICP between two LiDAR scans, the straightforward way: voxel means in a std::map,
// reference points hashed into voxels of the largest search radius in a std::unordered_map, every
// point's plane fitted to its neighbours over the 27 voxels around it, and every query point's nearest
// reference point searched over those 27 voxels in every iteration. The same options, weights and
// probe as rgbl::register_scans from its guess alone (no heading or along-track search). The
// benchmark baseline, and a check that rgbl's neighbourhoods (each searched once and kept while the
// point stays inside, pairs of points measured once for the planes) give the same registration.

#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/geometry/se3.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <vector>

namespace rgbl::reference {

struct ReferenceRegistration {
  Eigen::Isometry3d T_reference_query = Eigen::Isometry3d::Identity();
  bool converged = false;
  int iterations = 0;
  double agreement = 0.0;       // share of the query (reference_voxel) landing within agreement_tolerance
  double min_probe_loss = 0.0;  // the smallest share of those lost when moved probe_shift_m along an axis
};

namespace detail {

using Key = std::array<int, 3>;
inline Key key_of(const Eigen::Vector3d& p, double edge) {
  return {static_cast<int>(std::floor(p.x() / edge)), static_cast<int>(std::floor(p.y() / edge)),
          static_cast<int>(std::floor(p.z() / edge))};
}
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    return (static_cast<std::size_t>(k[0]) * 73856093U) ^ (static_cast<std::size_t>(k[1]) * 19349663U) ^
           (static_cast<std::size_t>(k[2]) * 83492791U);
  }
};

inline std::vector<Eigen::Vector3d> voxel_means(PointCloudView scan, const ScanRegistrationOptions& o, double edge) {
  std::map<Key, std::pair<Eigen::Vector3d, int>> voxels;
  for (const LidarPoint& l : scan) {
    const Eigen::Vector3d p(l.x, l.y, l.z);
    const double r = p.norm();
    if (!(r >= o.min_range && r <= o.max_range)) continue;
    auto& [sum, n] = voxels.try_emplace(key_of(p, edge), Eigen::Vector3d::Zero(), 0).first->second;
    sum += p;
    ++n;
  }
  std::vector<Eigen::Vector3d> out;
  for (const auto& [key, v] : voxels) out.push_back(v.first / v.second);
  return out;
}

// Points hashed into voxels of `edge`; near(p) visits the 27 voxels around p.
struct Grid {
  double edge;
  std::vector<Eigen::Vector3d> points;
  std::unordered_map<Key, std::vector<int>, KeyHash> voxels;
  Grid(std::vector<Eigen::Vector3d> pts, double e) : edge(e), points(std::move(pts)) {
    for (int i = 0; i < static_cast<int>(points.size()); ++i) voxels[key_of(points[i], edge)].push_back(i);
  }
  template <typename Visit>
  void near(const Eigen::Vector3d& p, Visit&& visit) const {
    if (!(p.cwiseAbs().maxCoeff() < 1e5)) return;
    const Key c = key_of(p, edge);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = voxels.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == voxels.end()) continue;
          for (const int j : it->second) visit(j);
        }
      }
    }
  }
};

}  // namespace detail

inline std::optional<ReferenceRegistration> register_scans(PointCloudView reference, PointCloudView query,
                                                           const Eigen::Isometry3d& guess,
                                                           const ScanRegistrationOptions& o) {
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using V6 = Eigen::Matrix<double, 6, 1>;
  const detail::Grid grid(detail::voxel_means(reference, o, o.reference_voxel),
                          std::max({o.coarse_distance, o.normal_radius, o.agreement_tolerance}));
  const std::vector<Eigen::Vector3d> query_points = detail::voxel_means(query, o, o.query_voxel);
  const std::vector<Eigen::Vector3d> dense = detail::voxel_means(query, o, o.reference_voxel);

  // every reference point's plane
  std::vector<std::optional<Eigen::Vector3d>> normals(grid.points.size());
  for (std::size_t i = 0; i < grid.points.size(); ++i) {
    std::vector<Eigen::Vector3d> neighbours;
    grid.near(grid.points[i], [&](int j) {
      if ((grid.points[j] - grid.points[i]).norm() <= o.normal_radius) neighbours.push_back(grid.points[j]);
    });
    if (static_cast<int>(neighbours.size()) < o.min_normal_points) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& q : neighbours) mean += q;
    mean /= static_cast<double>(neighbours.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& q : neighbours) covariance += (q - mean) * (q - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance / static_cast<double>(neighbours.size()));
    normals[i] = solver.eigenvectors().col(0);
  }

  ReferenceRegistration result;
  Eigen::Isometry3d T = guess;
  for (int iteration = 0; iteration < o.max_iterations; ++iteration) {
    const double max_distance = iteration < o.coarse_iterations ? o.coarse_distance : o.fine_distance;
    Matrix6d H = Matrix6d::Zero();
    V6 g = V6::Zero();
    std::size_t used = 0;
    for (const Eigen::Vector3d& q : query_points) {
      const Eigen::Vector3d x = T * q;
      int best = -1;
      double best_distance = max_distance;
      grid.near(x, [&](int j) {
        const double d = (grid.points[j] - x).norm();
        if (normals[j] && d < best_distance) {
          best_distance = d;
          best = j;
        }
      });
      if (best < 0) continue;
      const Eigen::Vector3d& n = *normals[best];
      const double r = n.dot(x - grid.points[best]);
      V6 J;
      J << n, x.cross(n);
      const double w = 1.0 / (1.0 + (r / o.robust_scale) * (r / o.robust_scale));
      H += w * J * J.transpose();
      g += w * r * J;
      ++used;
    }
    result.iterations = iteration + 1;
    if (used < o.min_correspondences) return std::nullopt;
    const V6 xi = -H.ldlt().solve(g);
    if (!xi.allFinite()) return std::nullopt;
    T = se3_exp(xi) * T;
    if (xi.head<3>().norm() < o.converged_m && xi.tail<3>().norm() < o.converged_deg * std::numbers::pi / 180.0) {
      result.converged = true;
      break;
    }
  }
  result.T_reference_query = T;

  const auto landing = [&](const Eigen::Isometry3d& pose) {
    std::size_t n = 0;
    for (const Eigen::Vector3d& q : dense) {
      const Eigen::Vector3d x = pose * q;
      bool lands = false;
      grid.near(x, [&](int j) { lands = lands || (grid.points[j] - x).norm() <= o.agreement_tolerance; });
      n += lands ? 1 : 0;
    }
    return n;
  };
  const std::size_t at_result = landing(T);
  result.agreement = dense.empty() ? 0.0 : static_cast<double>(at_result) / static_cast<double>(dense.size());
  result.min_probe_loss = at_result == 0 ? 0.0 : 1.0;
  for (int axis = 0; axis < 3 && at_result > 0; ++axis) {
    for (const double sign : {-1.0, 1.0}) {
      Eigen::Isometry3d moved = T;
      moved.translation()[axis] += sign * o.probe_shift_m;
      const double loss = 1.0 - static_cast<double>(landing(moved)) / static_cast<double>(at_result);
      result.min_probe_loss = std::min(result.min_probe_loss, std::max(loss, 0.0));
    }
  }
  return result;
}

}  // namespace rgbl::reference
