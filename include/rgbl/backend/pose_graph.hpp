#pragma once
// Pose-graph optimisation on SE(3) (Ceres, private to this module): the correction step of loop
// closing. Nodes are keyframe poses T_world_node; an edge holds a measured relative pose
// T_from_to = inv(T_world_from) * T_world_to (odometry, covisibility or a verified loop) with its
// standard deviations. Depth is metric, so there is no scale to correct: SE(3), not Sim(3).
//
// The residual of an edge is [dt; dphi] of E = inv(T_from_to_measured) * inv(T_world_from) * T_world_to,
// dt = translation of E, dphi = 2 * vec(q_E) (the rotation angle-vector for small errors), whitened by
// the edge's sigmas. Rotations are unit quaternions on Ceres' quaternion manifold, so graphs that turn
// by 180 degrees and more (a loop) have no parameter singularity.

#include <Eigen/Geometry>

#include <cstddef>
#include <span>
#include <vector>

namespace rgbl {

struct PoseGraphEdge {
  std::size_t from = 0;
  std::size_t to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();  // measured
  double sigma_translation = 0.05;  // m, per axis
  double sigma_rotation = 0.005;    // rad, per axis
};

struct PoseGraphOptions {
  int max_iterations = 100;
  // No robust loss: a false loop edge is as stiff as the chain it closes and ends up satisfied, so
  // Huber or Cauchy never see it as an outlier (tried: a 3 m wrong edge moved the graph by 2.9 m with
  // and without Huber). False closures must be stopped by verification, before the graph.
  int threads = 1;

  void validate() const;
};

struct PoseGraphResult {
  std::vector<Eigen::Isometry3d> T_world_node;
  double initial_cost = 0.0;  // Ceres cost: 0.5 * sum of squared whitened residuals
  double final_cost = 0.0;
  int iterations = 0;
  bool converged = false;     // Ceres reported convergence (not the iteration limit or a failure)
};

// Optimises every node except those listed in `fixed` (at least one is needed to fix the gauge; the
// first keyframe of a map is the usual choice). Throws ConfigError when an edge names a node that does
// not exist, an edge joins a node to itself, a sigma is not positive, or `fixed` is empty or out of range.
PoseGraphResult optimize_pose_graph(std::span<const Eigen::Isometry3d> T_world_node_initial,
                                    std::span<const PoseGraphEdge> edges, std::span<const std::size_t> fixed,
                                    const PoseGraphOptions& options = {});

// The whitened 6-vector residual [dt / sigma_t; dphi / sigma_r] of one edge at the given poses, through
// the same cost function the optimiser uses: for tests and for reporting how well a loop edge fits.
Eigen::Matrix<double, 6, 1> pose_graph_residual(const Eigen::Isometry3d& T_world_from, const Eigen::Isometry3d& T_world_to,
                                                const PoseGraphEdge& edge);

}  // namespace rgbl
