#include "rgbl/backend/pose_graph.hpp"

#include "rgbl/core/error.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace rgbl {
namespace {

// Node parameters: q (x, y, z, w; Eigen's storage order, for EigenQuaternionManifold) and t of
// T_world_node.
struct NodeBlock {
  std::array<double, 4> q{0.0, 0.0, 0.0, 1.0};
  std::array<double, 3> t{0.0, 0.0, 0.0};
};

struct RelativePoseCost {
  Eigen::Quaterniond q_meas_inv;  // inverse of the measured relative rotation R_from_to
  Eigen::Vector3d t_meas;
  double inv_sigma_t = 1.0;
  double inv_sigma_r = 1.0;

  template <typename T>
  bool operator()(const T* q_from_p, const T* t_from_p, const T* q_to_p, const T* t_to_p, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_from(q_from_p), q_to(q_to_p);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_from(t_from_p), t_to(t_to_p);
    const Eigen::Quaternion<T> q_from_inv = q_from.conjugate();
    // estimated relative pose inv(T_world_from) * T_world_to
    const Eigen::Quaternion<T> q_rel = q_from_inv * q_to;
    const Eigen::Matrix<T, 3, 1> t_rel = q_from_inv * (t_to - t_from);
    // error E = inv(measured) * estimated
    const Eigen::Quaternion<T> q_meas_inv_t = q_meas_inv.cast<T>();
    const Eigen::Quaternion<T> q_err = q_meas_inv_t * q_rel;
    const Eigen::Matrix<T, 3, 1> t_err = q_meas_inv_t * (t_rel - t_meas.cast<T>());
    for (int i = 0; i < 3; ++i) {
      residual[i] = t_err[i] * T(inv_sigma_t);
      residual[3 + i] = T(2.0) * q_err.vec()[i] * T(inv_sigma_r);
    }
    return true;
  }
};

RelativePoseCost make_cost(const PoseGraphEdge& edge) {
  RelativePoseCost cost;
  cost.q_meas_inv = Eigen::Quaterniond(edge.T_from_to.linear()).normalized().conjugate();
  cost.t_meas = edge.T_from_to.translation();
  cost.inv_sigma_t = 1.0 / edge.sigma_translation;
  cost.inv_sigma_r = 1.0 / edge.sigma_rotation;
  return cost;
}

NodeBlock to_block(const Eigen::Isometry3d& T) {
  NodeBlock b;
  const Eigen::Quaterniond q = Eigen::Quaterniond(T.linear()).normalized();
  b.q = {q.x(), q.y(), q.z(), q.w()};
  b.t = {T.translation().x(), T.translation().y(), T.translation().z()};
  return b;
}

Eigen::Isometry3d from_block(const NodeBlock& b) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(b.q[3], b.q[0], b.q[1], b.q[2]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(b.t[0], b.t[1], b.t[2]);
  return T;
}

void check_input(std::size_t nodes, std::span<const PoseGraphEdge> edges, std::span<const std::size_t> fixed) {
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    const auto fail = [&](const std::string& expected) {
      throw ConfigError(fmt::format("pose_graph.edges[{}]", i), expected);
    };
    if (e.from >= nodes || e.to >= nodes) fail(fmt::format("node indices below {} (has {} -> {})", nodes, e.from, e.to));
    if (e.from == e.to) fail(fmt::format("two different nodes (has {} -> {})", e.from, e.to));
    if (!(e.sigma_translation > 0.0 && e.sigma_rotation > 0.0)) fail("positive sigma_translation and sigma_rotation");
  }
  if (fixed.empty()) throw ConfigError("pose_graph.fixed", "at least one fixed node (the gauge)");
  for (const std::size_t f : fixed) {
    if (f >= nodes) throw ConfigError("pose_graph.fixed", fmt::format("node indices below {} (has {})", nodes, f));
  }
}

}  // namespace

void PoseGraphOptions::validate() const {
  require(max_iterations >= 1, "pose_graph.max_iterations", ">= 1");
  require(threads >= 1, "pose_graph.threads", ">= 1");
}

Eigen::Matrix<double, 6, 1> pose_graph_residual(const Eigen::Isometry3d& T_world_from, const Eigen::Isometry3d& T_world_to,
                                                const PoseGraphEdge& edge) {
  const NodeBlock a = to_block(T_world_from);
  const NodeBlock b = to_block(T_world_to);
  Eigen::Matrix<double, 6, 1> r;
  make_cost(edge)(a.q.data(), a.t.data(), b.q.data(), b.t.data(), r.data());
  return r;
}

PoseGraphResult optimize_pose_graph(std::span<const Eigen::Isometry3d> T_world_node_initial,
                                    std::span<const PoseGraphEdge> edges, std::span<const std::size_t> fixed,
                                    const PoseGraphOptions& options) {
  options.validate();
  const std::size_t n = T_world_node_initial.size();
  check_input(n, edges, fixed);

  std::vector<NodeBlock> blocks(n);
  for (std::size_t i = 0; i < n; ++i) blocks[i] = to_block(T_world_node_initial[i]);

  ceres::Problem problem;  // takes ownership of cost, loss and manifold objects
  for (const PoseGraphEdge& e : edges) {
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 4, 3, 4, 3>(new RelativePoseCost(make_cost(e)));
    problem.AddResidualBlock(cost, nullptr, blocks[e.from].q.data(), blocks[e.from].t.data(), blocks[e.to].q.data(),
                             blocks[e.to].t.data());
  }
  for (NodeBlock& b : blocks) {
    if (!problem.HasParameterBlock(b.q.data())) continue;  // a node without edges stays where it is
    problem.SetManifold(b.q.data(), new ceres::EigenQuaternionManifold);
  }
  for (const std::size_t f : fixed) {
    if (!problem.HasParameterBlock(blocks[f].q.data())) continue;
    problem.SetParameterBlockConstant(blocks[f].q.data());
    problem.SetParameterBlockConstant(blocks[f].t.data());
  }

  PoseGraphResult result;
  if (problem.NumResidualBlocks() > 0) {
    ceres::Solver::Options solver_options;
    // Loop graphs are long chains with a few cross edges: sparse Cholesky scales with the chain, a
    // dense solver with its cube.
    solver_options.linear_solver_type =
        ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
                ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)
            ? ceres::SPARSE_NORMAL_CHOLESKY
            : ceres::DENSE_QR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.num_threads = options.threads;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    result.initial_cost = summary.initial_cost;
    result.final_cost = summary.final_cost;
    result.iterations = static_cast<int>(summary.iterations.size());
    result.converged = summary.termination_type == ceres::CONVERGENCE;
  } else {
    result.converged = true;
  }
  result.T_world_node.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    // fixed and edge-less nodes are returned exactly as given, not re-orthonormalised
    const bool touched = problem.HasParameterBlock(blocks[i].q.data()) &&
                         std::find(fixed.begin(), fixed.end(), i) == fixed.end();
    result.T_world_node.push_back(touched ? from_block(blocks[i]) : T_world_node_initial[i]);
  }
  return result;
}

}  // namespace rgbl
