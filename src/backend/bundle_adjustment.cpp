#include "rgbl/backend/bundle_adjustment.hpp"

#include "rgbl/core/error.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <memory>

namespace rgbl {
namespace {

// Pose block: [angle-axis of R_cam_world (3), t_cam_world (3)]; point block: world position.
template <int kDim>
struct ReprojectionDepthCost {
  PinholeCamera camera;
  double u, v, inv_sigma_px;
  double z, inv_sigma_z;

  template <typename T>
  bool operator()(const T* pose, const T* point, T* residual) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, point, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    const Eigen::Matrix<T, 2, 1> px = project_point(camera, p[0], p[1], p[2]);
    residual[0] = (px.x() - u) * inv_sigma_px;
    residual[1] = (px.y() - v) * inv_sigma_px;
    if constexpr (kDim == 3) residual[2] = (p[2] - T(z)) * T(inv_sigma_z);
    return true;
  }
};

bool has_depth(const BundleObservation& o) { return o.depth > 0.0 && o.depth_sigma > 0.0; }

ceres::CostFunction* make_cost(const PinholeCamera& camera, const BundleObservation& o) {
  if (has_depth(o)) {
    return new ceres::AutoDiffCostFunction<ReprojectionDepthCost<3>, 3, 6, 3>(new ReprojectionDepthCost<3>{
        camera, o.pixel.x(), o.pixel.y(), 1.0 / o.sigma_px, o.depth,
        1.0 / o.depth_sigma});
  }
  return new ceres::AutoDiffCostFunction<ReprojectionDepthCost<2>, 2, 6, 3>(new ReprojectionDepthCost<2>{
      camera, o.pixel.x(), o.pixel.y(), 1.0 / o.sigma_px, 0.0, 0.0});
}

class AbortCallback : public ceres::IterationCallback {
 public:
  explicit AbortCallback(const std::atomic<bool>* abort) : abort_(abort) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (abort_ != nullptr && abort_->load(std::memory_order_relaxed)) {
      aborted_ = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool aborted() const { return aborted_; }

 private:
  const std::atomic<bool>* abort_;
  bool aborted_ = false;
};

}  // namespace

void BundleAdjustmentOptions::validate() const {
  require(iterations >= 1, "bundle_adjustment.iterations", ">= 1");
  require(chi2_2d > 0.0 && chi2_3d > 0.0, "bundle_adjustment.chi2", "> 0");
  require(threads >= 1, "bundle_adjustment.threads", ">= 1");
}

Vector6d pose_to_parameters(const Eigen::Isometry3d& T) {
  Vector6d x;
  x.head<3>() = so3_log(T.linear());
  x.tail<3>() = T.translation();
  return x;
}

Eigen::Isometry3d parameters_to_pose(const Vector6d& parameters) {
  return make_isometry(so3_exp(parameters.head<3>()), parameters.tail<3>());
}

int bundle_residual(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world, const Eigen::Vector3d& point,
                    const BundleObservation& observation, Eigen::Vector3d& residual,
                    Eigen::Matrix<double, 3, 6>& d_pose, Eigen::Matrix3d& d_point) {
  const std::unique_ptr<ceres::CostFunction> cost(make_cost(camera, observation));
  const int dim = cost->num_residuals();
  Vector6d pose = pose_to_parameters(T_cam_world);
  Eigen::Vector3d p = point;
  const double* parameters[2] = {pose.data(), p.data()};
  Eigen::Matrix<double, 3, 6, Eigen::RowMajor> jp = Eigen::Matrix<double, 3, 6, Eigen::RowMajor>::Zero();
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jx = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>::Zero();
  double* jacobians[2] = {jp.data(), jx.data()};
  residual.setZero();
  cost->Evaluate(parameters, residual.data(), jacobians);
  d_pose = jp;
  d_point = jx;
  return dim;
}

BundleAdjustmentResult bundle_adjust(const PinholeCamera& camera, BundleProblem& problem,
                                     const BundleAdjustmentOptions& options, const std::atomic<bool>* abort) {
  BundleAdjustmentResult result;
  result.outlier.assign(problem.observations.size(), false);
  if (problem.observations.empty()) return result;

  std::vector<Vector6d> poses(problem.poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) poses[i] = pose_to_parameters(problem.poses[i].T_cam_world);

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  const double delta2 = std::sqrt(options.chi2_2d), delta3 = std::sqrt(options.chi2_3d);
  std::vector<bool> pose_used(poses.size(), false), point_used(problem.points.size(), false);
  for (const BundleObservation& o : problem.observations) {
    double* pose = poses[static_cast<std::size_t>(o.pose)].data();
    double* point = problem.points[static_cast<std::size_t>(o.point)].data();
    ceres_problem.AddResidualBlock(make_cost(camera, o), new ceres::HuberLoss(has_depth(o) ? delta3 : delta2), pose,
                                   point);
    if (!point_used[static_cast<std::size_t>(o.point)]) {
      point_used[static_cast<std::size_t>(o.point)] = true;
      ordering->AddElementToGroup(point, 0);
    }
    if (!pose_used[static_cast<std::size_t>(o.pose)]) {
      pose_used[static_cast<std::size_t>(o.pose)] = true;
      ordering->AddElementToGroup(pose, 1);
      if (problem.poses[static_cast<std::size_t>(o.pose)].fixed) ceres_problem.SetParameterBlockConstant(pose);
    }
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = options.dense_schur ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  solver_options.linear_solver_ordering = ordering;
  solver_options.max_num_iterations = options.iterations;
  solver_options.num_threads = options.threads;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.logging_type = ceres::SILENT;
  AbortCallback callback(abort);
  solver_options.callbacks.push_back(&callback);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &ceres_problem, &summary);
  result.iterations = static_cast<int>(summary.iterations.size());
  result.aborted = callback.aborted();
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;

  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!problem.poses[i].fixed) problem.poses[i].T_cam_world = parameters_to_pose(poses[i]);
  }
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const BundleObservation& o = problem.observations[i];
    const Eigen::Isometry3d& T = problem.poses[static_cast<std::size_t>(o.pose)].T_cam_world;
    const Eigen::Vector3d p = T * problem.points[static_cast<std::size_t>(o.point)];
    if (p.z() <= 0.0) {
      result.outlier[i] = true;
      continue;
    }
    const Eigen::Vector2d px = camera.project_unchecked(p);
    double chi2 = (px - o.pixel).squaredNorm() / (o.sigma_px * o.sigma_px);
    if (has_depth(o)) {
      const double dz = (p.z() - o.depth) / o.depth_sigma;
      chi2 += dz * dz;
    }
    result.outlier[i] = chi2 > (has_depth(o) ? options.chi2_3d : options.chi2_2d);
  }
  return result;
}

}  // namespace rgbl
