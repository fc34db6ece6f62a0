#include "rgbl/backend/loop_correction.hpp"
#include "rgbl/backend/pose_graph.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace {

// A closed loop: n camera poses (T_world_cam, camera z forward, y down) around a circle of `radius`
// metres in the x-z plane, with a gentle up-and-down, so the heading sweeps a full 360 degrees.
std::vector<Eigen::Isometry3d> circle(std::size_t n, double radius) {
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * static_cast<double>(i) / static_cast<double>(n);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rgbl::so3_exp(Eigen::Vector3d(0.02 * std::sin(3.0 * a), -a, 0.0));  // yaw about -y (up)
    T.translation() = Eigen::Vector3d(radius * (1.0 - std::cos(a)), 0.5 * std::sin(2.0 * a), radius * std::sin(a));
    poses.push_back(T);
  }
  return poses;
}

rgbl::PoseGraphEdge edge(const std::vector<Eigen::Isometry3d>& truth, std::size_t from, std::size_t to) {
  rgbl::PoseGraphEdge e;
  e.from = from;
  e.to = to;
  e.T_from_to = truth[from].inverse() * truth[to];
  return e;
}

double position_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double max_position_error(const std::vector<Eigen::Isometry3d>& a, const std::vector<Eigen::Isometry3d>& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, position_error(a[i], b[i]));
  return worst;
}

}  // namespace

TEST_CASE("pose graph with exact edges recovers the exact poses from a perturbed start") {
  const auto truth = circle(60, 20.0);
  std::vector<rgbl::PoseGraphEdge> edges;
  for (std::size_t i = 0; i + 1 < truth.size(); ++i) edges.push_back(edge(truth, i, i + 1));
  for (std::size_t i = 0; i + 5 < truth.size(); i += 5) edges.push_back(edge(truth, i, i + 5));
  edges.push_back(edge(truth, truth.size() - 1, 0));  // the loop

  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Eigen::Isometry3d> start = truth;
  for (std::size_t i = 1; i < start.size(); ++i) {
    rgbl::Vector6d xi;
    for (int k = 0; k < 6; ++k) xi[k] = noise(rng) * (k < 3 ? 0.3 : 0.05);  // 0.3 m, ~3 deg
    start[i] = start[i] * rgbl::se3_exp(xi);
  }
  REQUIRE(max_position_error(start, truth) > 0.5);

  const std::vector<std::size_t> fixed{0};
  const rgbl::PoseGraphResult r = rgbl::optimize_pose_graph(start, edges, fixed);
  CHECK(r.converged);
  CHECK(r.final_cost < 1e-12);
  CHECK(r.initial_cost > 1e3);
  REQUIRE(r.T_world_node.size() == truth.size());
  CHECK(max_position_error(r.T_world_node, truth) < 1e-6);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    CHECK(rgbl::rotation_angle(r.T_world_node[i].linear().transpose() * truth[i].linear()) < 1e-7);
  }
  // the fixed node is returned bit-identical
  CHECK(r.T_world_node[0].matrix() == start[0].matrix());
}

TEST_CASE("pose graph spreads a loop's drift over the loop") {
  // Odometry that over-estimates each step by 1 % and turns 0.1 deg too far left per step (a drift of
  // the usual kind), one exact loop edge with a tight sigma: the end meets the start again and the
  // error along the loop falls to a fraction of the drift.
  const std::size_t n = 100;
  const auto truth = circle(n, 30.0);
  std::vector<rgbl::PoseGraphEdge> edges;
  const Eigen::Isometry3d bias = rgbl::make_isometry(rgbl::so3_exp(Eigen::Vector3d(0.0, -0.1 * M_PI / 180.0, 0.0)),
                                                     Eigen::Vector3d::Zero());
  std::vector<Eigen::Isometry3d> odometry{truth[0]};
  for (std::size_t i = 0; i + 1 < n; ++i) {
    rgbl::PoseGraphEdge e = edge(truth, i, i + 1);
    e.T_from_to.translation() *= 1.01;
    e.T_from_to = e.T_from_to * bias;
    edges.push_back(e);
    odometry.push_back(odometry.back() * e.T_from_to);
  }
  rgbl::PoseGraphEdge loop = edge(truth, n - 1, 0);
  loop.sigma_translation = 0.01;
  loop.sigma_rotation = 0.001;
  edges.push_back(loop);

  const double drift_end = position_error(odometry.back(), truth.back());
  const double drift_max = max_position_error(odometry, truth);
  REQUIRE(drift_end > 3.0);  // 5.45 m here: what there is to correct

  const std::vector<std::size_t> fixed{0};
  const rgbl::PoseGraphResult r = rgbl::optimize_pose_graph(odometry, edges, fixed);
  CHECK(r.converged);
  CHECK(r.final_cost < 0.01 * r.initial_cost);
  // the loop edge holds: the last pose sits where the loop measurement puts it relative to the first
  const auto loop_residual = rgbl::pose_graph_residual(r.T_world_node[n - 1], r.T_world_node[0], loop);
  CHECK(loop_residual.norm() < 0.5);  // 0.07 sigmas measured
  // measured: end error 5.45 m -> 0.0001 m, largest error along the loop 5.56 m -> 0.60 m (a 1 % scale
  // error in every step cannot vanish: it is spread round the loop)
  CHECK(position_error(r.T_world_node[n - 1], truth[n - 1]) < 0.01);
  CHECK(max_position_error(r.T_world_node, truth) < 0.15 * drift_max);
}

TEST_CASE("pose graph leaves fixed and unconnected nodes as given") {
  const auto truth = circle(10, 10.0);
  std::vector<Eigen::Isometry3d> start = truth;
  start[3].translation() += Eigen::Vector3d(0.4, 0.0, 0.0);
  start[9].translation() += Eigen::Vector3d(5.0, 0.0, 0.0);  // no edges reach node 9
  std::vector<rgbl::PoseGraphEdge> edges;
  for (std::size_t i = 0; i + 1 < 9; ++i) edges.push_back(edge(truth, i, i + 1));
  const std::vector<std::size_t> fixed{0, 5};
  const auto r = rgbl::optimize_pose_graph(start, edges, fixed);
  CHECK(r.T_world_node[5].matrix() == start[5].matrix());
  CHECK(r.T_world_node[9].matrix() == start[9].matrix());
  CHECK(position_error(r.T_world_node[3], truth[3]) < 1e-6);
}

TEST_CASE("pose graph rejects bad input naming the edge") {
  const auto truth = circle(5, 10.0);
  const std::vector<std::size_t> fixed{0};
  std::vector<rgbl::PoseGraphEdge> edges{edge(truth, 0, 1), edge(truth, 1, 2)};
  edges[1].to = 7;
  CHECK_THROWS_WITH(rgbl::optimize_pose_graph(truth, edges, fixed),
                    Catch::Contains("pose_graph.edges[1]") && Catch::Contains("below 5"));
  edges[1].to = 1;
  CHECK_THROWS_WITH(rgbl::optimize_pose_graph(truth, edges, fixed), Catch::Contains("two different nodes"));
  edges[1].to = 2;
  edges[0].sigma_rotation = 0.0;
  CHECK_THROWS_WITH(rgbl::optimize_pose_graph(truth, edges, fixed), Catch::Contains("pose_graph.edges[0]"));
  edges[0].sigma_rotation = 0.01;
  CHECK_THROWS_AS(rgbl::optimize_pose_graph(truth, edges, std::vector<std::size_t>{}), rgbl::ConfigError);
  CHECK_THROWS_AS(rgbl::optimize_pose_graph(truth, edges, std::vector<std::size_t>{9}), rgbl::ConfigError);
  rgbl::PoseGraphOptions bad;
  bad.max_iterations = 0;
  CHECK_THROWS_WITH(rgbl::optimize_pose_graph(truth, edges, fixed, bad), Catch::Contains("pose_graph.max_iterations"));
}

namespace {

// Poses chained from odometry that makes every step 1 % long and turns 0.2 deg too far: the drift a
// loop closure has to take out.
std::vector<Eigen::Isometry3d> drifted(const std::vector<Eigen::Isometry3d>& truth) {
  const Eigen::Isometry3d bias = rgbl::make_isometry(rgbl::so3_exp(Eigen::Vector3d(0.0, -0.2 * M_PI / 180.0, 0.0)),
                                                     Eigen::Vector3d::Zero());
  std::vector<Eigen::Isometry3d> out{truth[0]};
  for (std::size_t i = 0; i + 1 < truth.size(); ++i) {
    Eigen::Isometry3d step = truth[i].inverse() * truth[i + 1];
    step.translation() *= 1.01;
    out.push_back(out.back() * step * bias);
  }
  return out;
}

}  // namespace

TEST_CASE("loop correction moves keyframes and their landmarks back onto the truth") {
  const std::size_t n = 60;
  const auto truth = circle(n, 20.0);
  const auto odometry = drifted(truth);
  const std::vector<Eigen::Vector3d> in_camera{{-2.0, -1.0, 10.0}, {2.0, -1.0, 12.0}, {-3.0, 1.2, 8.0}, {3.0, 1.2, 15.0}};

  rgbl::Map map;
  std::vector<rgbl::KeyframeId> ids;
  for (std::size_t i = 0; i < n; ++i) {
    rgbl::Keyframe k;
    k.T_cam_world = odometry[i].inverse();
    k.keypoints.resize(in_camera.size());
    k.descriptors.resize(in_camera.size());
    ids.push_back(map.add_keyframe(std::move(k)));
    if (i > 0) map.keyframe(ids[i])->parent = ids[i - 1];
    for (std::size_t j = 0; j < in_camera.size(); ++j) {
      const rgbl::LandmarkId l = map.add_landmark(odometry[i] * in_camera[j], ids[i]);  // mapped with the drift
      map.add_observation(l, ids[i], static_cast<int>(j));
    }
  }
  double drift_max = 0.0;
  for (std::size_t i = 0; i < n; ++i) drift_max = std::max(drift_max, position_error(odometry[i], truth[i]));
  REQUIRE(drift_max > 3.0);  // 4.44 m measured

  rgbl::LoopConstraint loop;
  loop.current = ids.back();
  loop.matched = ids.front();
  loop.T_current_matched = truth.back().inverse() * truth.front();  // what verification would measure
  const rgbl::LoopCorrectionResult r = rgbl::correct_loops(map, {loop});
  CHECK(r.converged);
  CHECK(r.keyframes == n);
  CHECK(r.edges == n);  // n - 1 tree edges and the loop
  CHECK(r.landmarks == n * in_camera.size());
  CHECK(r.loop_error_before_m > 3.0);
  CHECK(r.loop_error_after_m < 0.01);
  CHECK(r.max_keyframe_shift_m > 3.0);

  // measured: keyframes 4.44 m -> 0.43 m at worst, landmarks 0.45 m (the 1 % scale error stays,
  // spread round the loop)
  double keyframe_error = 0.0, landmark_error = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const rgbl::Keyframe& k = *map.keyframe(ids[i]);
    keyframe_error = std::max(keyframe_error, position_error(k.T_cam_world.inverse(), truth[i]));
    for (std::size_t j = 0; j < in_camera.size(); ++j) {
      const rgbl::Landmark& l = *map.landmark(k.landmarks[j]);
      landmark_error = std::max(landmark_error, (l.position - truth[i] * in_camera[j]).norm());
      // a landmark rides rigidly with its reference keyframe
      CHECK((k.T_cam_world * l.position - in_camera[j]).norm() < 1e-9);
    }
  }
  CHECK(keyframe_error < 0.15 * drift_max);
  CHECK(landmark_error < 0.15 * drift_max);
  // the root keyframe does not move
  CHECK(position_error(map.keyframe(ids[0])->T_cam_world.inverse(), truth[0]) < 1e-12);
}

TEST_CASE("loop correction rejects a loop to a keyframe the map does not hold") {
  rgbl::Map map;
  rgbl::Keyframe k;
  const rgbl::KeyframeId a = map.add_keyframe(k);
  rgbl::LoopConstraint loop;
  loop.current = a;
  loop.matched = rgbl::KeyframeId{5};
  CHECK_THROWS_WITH(rgbl::correct_loops(map, {loop}), Catch::Contains("loops[0]") && Catch::Contains("-> 5"));
  rgbl::LoopCorrectionOptions bad;
  bad.sigma_rotation = 0.0;
  CHECK_THROWS_WITH(rgbl::correct_loops(map, {}, bad), Catch::Contains("loop_correction.sigma_rotation"));
}
