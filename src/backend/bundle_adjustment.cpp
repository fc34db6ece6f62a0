#include "rgbl/backend/bundle_adjustment.hpp"

#include "rgbl/core/error.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <memory>

namespace rgbl {
namespace {

bool has_depth(const BundleObservation& o) { return o.depth > 0.0 && o.depth_sigma > 0.0; }

// Parameter blocks: rotation of R_cam_world as angle-axis (3), t_cam_world (3), the point's world
// position (3). Every residual has three rows, the third zero without depth: with all row and
// parameter blocks of size 3 Ceres runs its fixed-size Schur eliminator (SchurEliminator<3, 3, 3>)
// instead of the dynamic one, and the zero row adds exact zeros to the normal equations.
// Analytic Jacobians: automatic differentiation of the angle-axis rotation was as costly as the
// linear algebra of a local BA.
class ReprojectionDepthCost final : public ceres::SizedCostFunction<3, 3, 3, 3> {
 public:
  ReprojectionDepthCost(const PinholeCamera& camera, const BundleObservation& o)
      : camera_(camera), pixel_(o.pixel), inv_sigma_px_(1.0 / o.sigma_px), depth_(o.depth),
        inv_sigma_z_(has_depth(o) ? 1.0 / o.depth_sigma : 0.0) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> w(parameters[0]), t(parameters[1]), x(parameters[2]);
    const Eigen::Matrix3d R = so3_exp(w);
    const Eigen::Vector3d Rx = R * x;
    const Eigen::Vector3d p = Rx + t;
    const Eigen::Vector2d px = camera_.project_unchecked(p);
    residuals[0] = (px.x() - pixel_.x()) * inv_sigma_px_;
    residuals[1] = (px.y() - pixel_.y()) * inv_sigma_px_;
    residuals[2] = inv_sigma_z_ > 0.0 ? (p.z() - depth_) * inv_sigma_z_ : 0.0;
    if (jacobians == nullptr) return true;

    // d(residual) / d(p): the whitened projection, then the depth row.
    Eigen::Matrix3d dr_dp;
    dr_dp.topRows<2>() = inv_sigma_px_ * camera_.projection_jacobian(p);
    dr_dp.row(2) << 0.0, 0.0, inv_sigma_z_;
    using RowMajor3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    if (jacobians[0] != nullptr) {
      // R(w + dw) x = R x - hat(R x) J_l(w) dw
      Eigen::Map<RowMajor3d>{jacobians[0]} = -dr_dp * hat(Rx) * so3_left_jacobian(w);
    }
    if (jacobians[1] != nullptr) Eigen::Map<RowMajor3d>{jacobians[1]} = dr_dp;
    if (jacobians[2] != nullptr) Eigen::Map<RowMajor3d>{jacobians[2]} = dr_dp * R;
    return true;
  }

 private:
  PinholeCamera camera_;
  Eigen::Vector2d pixel_;
  double inv_sigma_px_, depth_, inv_sigma_z_;
};

// BundlePlanePair's residual. Automatic differentiation: a handful per problem.
struct PlanePairCost {
  Eigen::Vector4d a, b;
  Eigen::Vector3d b1, b2;  // across b's normal
  double inv_tilt, inv_offset;

  explicit PlanePairCost(const BundlePlanePair& pair) : a(pair.plane_a), b(pair.plane_b) {
    const Eigen::Vector3d m = b.head<3>().normalized();
    const Eigen::Vector3d axis = std::abs(m.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    b1 = (axis - axis.dot(m) * m).normalized();
    b2 = m.cross(b1);
    inv_tilt = 1.0 / pair.sigma_tilt;
    inv_offset = 1.0 / pair.sigma_offset;
  }

  template <typename T>
  bool operator()(const T* wa, const T* ta, const T* wb, const T* tb, T* residual) const {
    // a's plane in the world: n_w = R_a^T n_a, d_w = d_a - n_a . t_a
    const T na[3] = {T(a.x()), T(a.y()), T(a.z())};
    const T minus_wa[3] = {-wa[0], -wa[1], -wa[2]};
    T nw[3];
    ceres::AngleAxisRotatePoint(minus_wa, na, nw);
    const T dw = T(a.w()) - (na[0] * ta[0] + na[1] * ta[1] + na[2] * ta[2]);
    // seen from b: n = R_b n_w, d = d_w + n . t_b
    T n[3];
    ceres::AngleAxisRotatePoint(wb, nw, n);
    const T d = dw + n[0] * tb[0] + n[1] * tb[1] + n[2] * tb[2];
    residual[0] = (T(b1.x()) * n[0] + T(b1.y()) * n[1] + T(b1.z()) * n[2]) * inv_tilt;
    residual[1] = (T(b2.x()) * n[0] + T(b2.y()) * n[1] + T(b2.z()) * n[2]) * inv_tilt;
    residual[2] = (d - T(b.w())) * inv_offset;
    return true;
  }
};

// BundlePosePair's residual: E = inv(T_b_a measured) * T_b * inv(T_a), [t_E / sigma_t; log(R_E) / sigma_r].
struct PosePairCost {
  Eigen::Matrix3d R_m;  // rotation of inv(T_b_a)
  Eigen::Vector3d t_m;  // translation of inv(T_b_a)
  Eigen::Matrix<double, 6, 1> inv_sigma;

  explicit PosePairCost(const BundlePosePair& pair)
      : R_m(pair.T_b_a.linear().transpose()), t_m(-(pair.T_b_a.linear().transpose() * pair.T_b_a.translation())) {
    const double t = 1.0 / pair.sigma_translation, r = 1.0 / pair.sigma_rotation;
    inv_sigma << t, t, t, r, r, r;
    if (pair.level_only) inv_sigma(1) = inv_sigma(3) = inv_sigma(5) = 0.0;
  }

  template <typename T>
  bool operator()(const T* wa, const T* ta, const T* wb, const T* tb, T* residual) const {
    using M3 = Eigen::Matrix<T, 3, 3>;  // column-major, as ColumnMajorAdapter3x3 expects
    using V3 = Eigen::Matrix<T, 3, 1>;
    M3 R_a, R_b;
    ceres::AngleAxisToRotationMatrix(wa, ceres::ColumnMajorAdapter3x3(R_a.data()));
    ceres::AngleAxisToRotationMatrix(wb, ceres::ColumnMajorAdapter3x3(R_b.data()));
    // T_b * inv(T_a): R_b R_a^T, t_b - R_b R_a^T t_a; then inv(T_b_a) * that
    const M3 R_ba = R_b * R_a.transpose();
    const V3 t_ba = Eigen::Map<const V3>(tb) - R_ba * Eigen::Map<const V3>(ta);
    const M3 R_e = R_m.cast<T>() * R_ba;
    const V3 t_e = R_m.cast<T>() * t_ba + t_m.cast<T>();
    T w[3];
    ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(R_e.data()), w);
    for (int i = 0; i < 3; ++i) {
      residual[i] = t_e[i] * inv_sigma(i);
      residual[3 + i] = w[i] * inv_sigma(3 + i);
    }
    return true;
  }
};

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
  const auto cost = std::make_unique<ReprojectionDepthCost>(camera, observation);
  Vector6d pose = pose_to_parameters(T_cam_world);
  Eigen::Vector3d p = point;
  const double* parameters[3] = {pose.data(), pose.data() + 3, p.data()};
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jr, jt, jx;
  double* jacobians[3] = {jr.data(), jt.data(), jx.data()};
  residual.setZero();
  cost->Evaluate(parameters, residual.data(), jacobians);
  d_pose << jr, jt;
  d_point = jx;
  return has_depth(observation) ? 3 : 2;
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
    double* rotation = poses[static_cast<std::size_t>(o.pose)].data();
    double* translation = rotation + 3;
    double* point = problem.points[static_cast<std::size_t>(o.point)].data();
    ceres_problem.AddResidualBlock(new ReprojectionDepthCost(camera, o),
                                   new ceres::HuberLoss(has_depth(o) ? delta3 : delta2), rotation, translation, point);
    if (!point_used[static_cast<std::size_t>(o.point)]) {
      point_used[static_cast<std::size_t>(o.point)] = true;
      ordering->AddElementToGroup(point, 0);
    }
    if (!pose_used[static_cast<std::size_t>(o.pose)]) {
      pose_used[static_cast<std::size_t>(o.pose)] = true;
      ordering->AddElementToGroup(rotation, 1);
      ordering->AddElementToGroup(translation, 1);
      if (problem.poses[static_cast<std::size_t>(o.pose)].fixed) {
        ceres_problem.SetParameterBlockConstant(rotation);
        ceres_problem.SetParameterBlockConstant(translation);
      }
    }
  }

  // a pair between two distinct poses of the problem that have observations
  const auto usable = [&](int a, int b) {
    const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
    return a >= 0 && b >= 0 && ia < poses.size() && ib < poses.size() && ia != ib && pose_used[ia] && pose_used[ib];
  };
  // a pair's cost on the rotation and translation blocks of its two poses
  const auto add_pair = [&](ceres::CostFunction* cost, double delta, int a, int b) {
    const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
    ceres_problem.AddResidualBlock(cost, new ceres::HuberLoss(delta), poses[ia].data(), poses[ia].data() + 3,
                                   poses[ib].data(), poses[ib].data() + 3);
  };
  for (const BundlePlanePair& pair : problem.plane_pairs) {
    if (!usable(pair.pose_a, pair.pose_b)) continue;
    add_pair(new ceres::AutoDiffCostFunction<PlanePairCost, 3, 3, 3, 3, 3>(new PlanePairCost(pair)), delta3,
             pair.pose_a, pair.pose_b);
  }
  const double delta6 = std::sqrt(12.592);  // 95 % of chi2 with 6 dof
  for (const BundlePosePair& pair : problem.pose_pairs) {
    if (!usable(pair.pose_a, pair.pose_b)) continue;
    add_pair(new ceres::AutoDiffCostFunction<PosePairCost, 6, 3, 3, 3, 3>(new PosePairCost(pair)), delta6,
             pair.pose_a, pair.pose_b);
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
