#include "rgbl/backend/bundle_adjustment.hpp"

#include "support/kitti_camera.hpp"

#include <catch2/catch.hpp>

#include <random>

namespace {

Eigen::Isometry3d pose_along_road(double z) {
  rgbl::Vector6d xi;
  xi << 0.05 * z, 0.01 * z, -z, 0.002 * z, 0.004 * z, -0.001 * z;  // T_cam_world: camera at +z
  return rgbl::se3_exp(xi);
}

// 40 points in front of each pose, seen by that pose alone (pixel and depth exact at its current
// pose): every pose is in the problem, and nothing but the pairs ties one to another.
void add_own_points(rgbl::BundleProblem& problem, const rgbl::PinholeCamera& camera, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t pose = 0; pose < problem.poses.size(); ++pose) {
    const Eigen::Isometry3d T = problem.poses[pose].T_cam_world;
    for (int k = 0; k < 40; ++k) {
      const Eigen::Vector3d p_cam(6.0 * u(rng), 1.5 * u(rng), 12.0 + 8.0 * u(rng));
      rgbl::BundleObservation o;
      o.pose = static_cast<int>(pose);
      o.point = static_cast<int>(problem.points.size());
      o.pixel = camera.project_unchecked(p_cam);
      o.depth = p_cam.z();
      o.depth_sigma = 0.05;
      problem.points.push_back(T.inverse() * p_cam);
      problem.observations.push_back(o);
    }
  }
}

// How far b (pose 1) moves when the problem is solved again from b_start and the original points with
// no pairs at all: its own points agree with it, so it should not.
double shift_without_pairs(rgbl::BundleProblem problem, const Eigen::Isometry3d& b_start,
                           const std::vector<Eigen::Vector3d>& points, const rgbl::PinholeCamera& camera,
                           const rgbl::BundleAdjustmentOptions& options) {
  problem.plane_pairs.clear();
  problem.pose_pairs.clear();
  problem.poses[1].T_cam_world = b_start;
  problem.points = points;
  rgbl::bundle_adjust(camera, problem, options);
  return (problem.poses[1].T_cam_world.inverse().translation() - b_start.inverse().translation()).norm();
}

}  // namespace

TEST_CASE("bundle residual Jacobians match numeric differentiation") {
  // KITTI's rectified camera, and one with lens distortion (the analytic Jacobian chains it in)
  auto distorted = rgbl::test::kitti_camera();
  distorted.distortion = {-0.28, 0.07, 0.0012, -0.0009, 0.01};
  // a rotation near zero takes the series branch of the left Jacobian
  for (const auto& [cam, T] : {std::pair{rgbl::test::kitti_camera(), pose_along_road(3.0)},
                               std::pair{distorted, pose_along_road(3.0)},
                               std::pair{rgbl::test::kitti_camera(), pose_along_road(1e-7)}}) {
    const Eigen::Vector3d p = T.inverse() * Eigen::Vector3d(2.0, -1.0, 15.0);
    for (const bool with_depth : {false, true}) {
      rgbl::BundleObservation o;
      o.pixel = cam.project_unchecked(T * p) + Eigen::Vector2d(0.8, -1.1);
      o.sigma_px = 1.2;
      if (with_depth) {
        o.depth = 15.2;
        o.depth_sigma = 0.1;
      }
      Eigen::Vector3d r;
      Eigen::Matrix<double, 3, 6> jp;
      Eigen::Matrix3d jx;
      const int dim = rgbl::bundle_residual(cam, T, p, o, r, jp, jx);
      CHECK(dim == (with_depth ? 3 : 2));
      const rgbl::Vector6d x0 = rgbl::pose_to_parameters(T);
      const double h = 1e-6;
      Eigen::Matrix<double, 3, 6> np;
      Eigen::Matrix3d nx;
      Eigen::Matrix<double, 3, 6> unused_p;
      Eigen::Matrix3d unused_x;
      for (int k = 0; k < 6; ++k) {
        rgbl::Vector6d d = rgbl::Vector6d::Zero();
        d(k) = h;
        Eigen::Vector3d rp, rm;
        rgbl::bundle_residual(cam, rgbl::parameters_to_pose(x0 + d), p, o, rp, unused_p, unused_x);
        rgbl::bundle_residual(cam, rgbl::parameters_to_pose(x0 - d), p, o, rm, unused_p, unused_x);
        np.col(k) = (rp - rm) / (2.0 * h);
      }
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d(k) = h;
        Eigen::Vector3d rp, rm;
        rgbl::bundle_residual(cam, T, p + d, o, rp, unused_p, unused_x);
        rgbl::bundle_residual(cam, T, p - d, o, rm, unused_p, unused_x);
        nx.col(k) = (rp - rm) / (2.0 * h);
      }
      CHECK((np - jp).norm() < 1e-4 * (1.0 + jp.norm()));
      CHECK((nx - jx).norm() < 1e-4 * (1.0 + jx.norm()));
      // The residual is the whitened reprojection (and depth) error.
      CHECK(r(0) == Approx(-0.8 / 1.2));
      if (with_depth) CHECK(r(2) == Approx((15.0 - 15.2) / 0.1));
      if (!with_depth) CHECK(r(2) == 0.0);
    }
  }
}

TEST_CASE("local bundle adjustment recovers poses and points, keeps fixed poses, flags outliers") {
  const auto cam = rgbl::test::kitti_camera();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(20.0, cam.width - 20.0), v(20.0, cam.height - 20.0), z(6.0, 30.0);
  std::normal_distribution<double> noise(0.0, 0.5), pose_noise(0.0, 0.05), point_noise(0.0, 0.2);
  rgbl::BundleProblem truth;
  for (int k = 0; k < 6; ++k) truth.poses.push_back({pose_along_road(1.5 * k), k < 2});
  for (int i = 0; i < 300; ++i) {
    truth.points.push_back(truth.poses[0].T_cam_world.inverse() *
                           cam.unproject(Eigen::Vector2d(u(rng), v(rng)), z(rng) + 9.0));
  }
  rgbl::BundleProblem problem = truth;
  std::vector<bool> is_outlier;
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector3d pc = truth.poses[static_cast<std::size_t>(k)].T_cam_world * truth.points[static_cast<std::size_t>(i)];
      const auto px = cam.project(pc);
      if (!px) continue;
      rgbl::BundleObservation o;
      o.pose = k;
      o.point = i;
      o.pixel = *px + Eigen::Vector2d(noise(rng), noise(rng));
      if (i % 3 == 0) {
        o.depth = pc.z() + 0.3 * noise(rng) * 0.1;
        o.depth_sigma = 0.05;
      }
      const bool outlier = (i * 7 + k) % 37 == 0;
      if (outlier) o.pixel += Eigen::Vector2d(30.0, -20.0);
      problem.observations.push_back(o);
      is_outlier.push_back(outlier);
    }
  }
  for (std::size_t k = 2; k < problem.poses.size(); ++k) {
    rgbl::Vector6d d;
    d << pose_noise(rng), pose_noise(rng), pose_noise(rng), 0.1 * pose_noise(rng), 0.1 * pose_noise(rng), 0.0;
    problem.poses[k].T_cam_world = rgbl::se3_exp(d) * problem.poses[k].T_cam_world;
  }
  for (auto& p : problem.points) p += Eigen::Vector3d(point_noise(rng), point_noise(rng), point_noise(rng));
  rgbl::BundleAdjustmentOptions options;
  options.iterations = 20;
  const auto result = rgbl::bundle_adjust(cam, problem, options);
  CHECK_FALSE(result.aborted);
  CHECK(result.final_cost < result.initial_cost);
  for (std::size_t k = 0; k < 2; ++k) {
    CHECK((problem.poses[k].T_cam_world.matrix() - truth.poses[k].T_cam_world.matrix()).norm() == 0.0);
  }
  for (std::size_t k = 2; k < problem.poses.size(); ++k) {
    const Eigen::Isometry3d E = problem.poses[k].T_cam_world * truth.poses[k].T_cam_world.inverse();
    CHECK(E.translation().norm() < 0.02);
    CHECK(rgbl::rotation_angle(E.linear()) < 1e-3);
  }
  int flagged = 0, total = 0;
  for (std::size_t i = 0; i < is_outlier.size(); ++i) {
    if (!is_outlier[i]) continue;
    ++total;
    flagged += result.outlier[i] ? 1 : 0;
  }
  CHECK(total > 10);
  CHECK(flagged == total);
}

TEST_CASE("bundle adjustment stops when the abort flag is set") {
  const auto cam = rgbl::test::kitti_camera();
  rgbl::BundleProblem problem;
  problem.poses = {{pose_along_road(0.0), true}, {pose_along_road(1.0), false}};
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d p(-5.0 + 0.2 * i, 1.0 - 0.05 * i, 12.0 + 0.3 * i);
    problem.points.push_back(p);
    for (int k = 0; k < 2; ++k) {
      rgbl::BundleObservation o;
      o.pose = k;
      o.point = i;
      o.pixel = cam.project_unchecked(problem.poses[static_cast<std::size_t>(k)].T_cam_world * p) + Eigen::Vector2d(3.0, 0.0);
      problem.observations.push_back(o);
    }
  }
  const std::atomic<bool> abort{true};
  const auto result = rgbl::bundle_adjust(cam, problem, {}, &abort);
  CHECK(result.aborted);
  CHECK(result.iterations <= 2);
}

TEST_CASE("bundle adjustment: a road seen by two poses ties the second's height and tilt to the first") {
  // Pose a (fixed) and pose b 8 m further, both over one road 1.65 m below the camera; b's points are
  // seen by b alone, so nothing but the road ties b to a. b starts 0.4 m too high and pitched and
  // rolled by 1.5 and 1 deg: the road brings height, pitch and roll back; what the road cannot see
  // (along it, across it, the heading) stays as it was.
  const auto camera = rgbl::test::kitti_camera();
  const Eigen::Isometry3d T_a = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_b_true = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.03, 0.0}), Eigen::Vector3d(0.0, 0.0, -8.0));
  const Eigen::Vector4d road_cam(0.0, 1.0, 0.0, 1.65);  // n . x = d in either camera (the road is flat)
  // the same road in b's frame: the world plane y = 1.65 seen from T_b_true
  const Eigen::Vector3d n_b = T_b_true.linear() * Eigen::Vector3d::UnitY();
  const double d_b = 1.65 + n_b.dot(T_b_true.translation());
  rgbl::BundleProblem problem;
  problem.poses.push_back({T_a, true});
  const Eigen::Isometry3d error = rgbl::make_isometry(rgbl::so3_exp({0.026, 0.0, 0.017}), Eigen::Vector3d(0.0, -0.4, 0.0));
  problem.poses.push_back({error * T_b_true, false});
  add_own_points(problem, camera, 5);
  rgbl::BundlePlanePair pair;
  pair.pose_a = 0;
  pair.pose_b = 1;
  pair.plane_a = road_cam;
  pair.plane_b = Eigen::Vector4d(n_b.x(), n_b.y(), n_b.z(), d_b);
  pair.sigma_tilt = 0.5 * M_PI / 180.0;
  pair.sigma_offset = 0.05;
  problem.plane_pairs.push_back(pair);
  rgbl::BundleAdjustmentOptions options;
  options.iterations = 50;
  const std::vector<Eigen::Vector3d> points = problem.points;
  rgbl::bundle_adjust(camera, problem, options);
  // b's camera centre and axes in the world against the truth's
  const Eigen::Isometry3d T_world_b = problem.poses[1].T_cam_world.inverse(), T_world_true = T_b_true.inverse();
  const Eigen::Vector3d c = T_world_b.translation(), c_true = T_world_true.translation();
  CHECK(c.y() == Approx(c_true.y()).margin(1e-4));   // height over the road
  const Eigen::Vector3d down = T_world_b.linear().col(1), down_true = T_world_true.linear().col(1);
  CHECK(std::acos(std::min(1.0, down.dot(down_true))) < 1e-4);  // pitch and roll: the camera's down axis
  CHECK(problem.poses[0].T_cam_world.isApprox(T_a));  // a is fixed
  CHECK(shift_without_pairs(problem, error * T_b_true, points, camera, options) < 1e-6);
}

TEST_CASE("bundle adjustment: the motion measured between two poses places the second where only it ties b") {
  // Pose a (fixed) and pose b 10 m further; b's points are seen by b alone, so nothing but the pose pair
  // ties b to a. b starts 0.3 m to the side, 0.2 m short and turned by 1 deg: the pair (the true motion)
  // brings all six back; without it nothing moves b.
  const auto camera = rgbl::test::kitti_camera();
  const Eigen::Isometry3d T_a = rgbl::make_isometry(rgbl::so3_exp({0.01, -0.2, 0.0}), Eigen::Vector3d(1.0, 0.0, 2.0));
  const Eigen::Isometry3d T_b_a = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.05, 0.0}), Eigen::Vector3d(0.1, 0.0, -10.0));
  const Eigen::Isometry3d T_b_true = T_b_a * T_a;
  const Eigen::Isometry3d error =
      rgbl::make_isometry(rgbl::so3_exp({0.0, 0.0175, 0.0}), Eigen::Vector3d(0.3, 0.0, 0.2));
  rgbl::BundleProblem problem;
  problem.poses.push_back({T_a, true});
  problem.poses.push_back({error * T_b_true, false});
  add_own_points(problem, camera, 7);
  rgbl::BundlePosePair pair;
  pair.pose_a = 0;
  pair.pose_b = 1;
  pair.T_b_a = T_b_a;
  pair.sigma_translation = 0.05;
  pair.sigma_rotation = 0.005;
  problem.pose_pairs.push_back(pair);
  rgbl::BundleAdjustmentOptions options;
  options.iterations = 50;
  const std::vector<Eigen::Vector3d> points = problem.points;
  rgbl::bundle_adjust(camera, problem, options);
  const Eigen::Isometry3d E = problem.poses[1].T_cam_world * T_b_true.inverse();
  CHECK(E.translation().norm() < 1e-5);
  CHECK(rgbl::so3_log(E.linear()).norm() < 1e-6);
  CHECK(problem.poses[0].T_cam_world.isApprox(T_a));  // a is fixed
  CHECK(shift_without_pairs(problem, error * T_b_true, points, camera, options) < 1e-6);
}

TEST_CASE("bundle adjustment: a level-only motion pair corrects along, across and the heading, not height or tilt") {
  // As above, with b's error written as E = inv(T_b_a) * T_b * inv(T_a), the pair's own residual frame.
  const auto camera = rgbl::test::kitti_camera();
  const Eigen::Isometry3d T_a = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_b_a = rgbl::make_isometry(rgbl::so3_exp({0.0, 0.05, 0.0}), Eigen::Vector3d(0.1, 0.0, -10.0));
  const auto solve = [&](const Eigen::Isometry3d& E_initial) {
    rgbl::BundleProblem problem;
    problem.poses.push_back({T_a, true});
    problem.poses.push_back({T_b_a * E_initial * T_a, false});
    add_own_points(problem, camera, 11);
    rgbl::BundlePosePair pair;
    pair.pose_a = 0;
    pair.pose_b = 1;
    pair.T_b_a = T_b_a;
    pair.level_only = true;
    problem.pose_pairs.push_back(pair);
    rgbl::BundleAdjustmentOptions options;
    options.iterations = 50;
    rgbl::bundle_adjust(camera, problem, options);
    return Eigen::Isometry3d(T_b_a.inverse() * problem.poses[1].T_cam_world * T_a.inverse());
  };
  // height, pitch and roll only: the pair does not see them, b stays
  const Eigen::Isometry3d E_level = rgbl::make_isometry(rgbl::so3_exp({0.02, 0.0, 0.015}), Eigen::Vector3d(0.0, -0.4, 0.0));
  CHECK(solve(E_level).isApprox(E_level, 1e-7));
  // all six: along, across and the heading go to zero, height stays
  const Eigen::Isometry3d E_all = rgbl::make_isometry(rgbl::so3_exp({0.02, 0.0175, 0.015}), Eigen::Vector3d(0.3, -0.4, 0.2));
  const Eigen::Isometry3d E = solve(E_all);
  CHECK(std::abs(E.translation().x()) < 1e-6);
  CHECK(std::abs(E.translation().z()) < 1e-6);
  CHECK(std::abs(rgbl::so3_log(E.linear()).y()) < 1e-7);
  CHECK(E.translation().y() == Approx(-0.4).margin(0.01));
}
