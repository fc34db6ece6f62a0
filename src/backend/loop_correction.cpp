#include "rgbl/backend/loop_correction.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>
#include <utility>

namespace rgbl {

void LoopCorrectionOptions::validate() const {
  require(min_covisibility >= 1, "loop_correction.min_covisibility", ">= 1 shared landmark");
  require(sigma_translation > 0.0, "loop_correction.sigma_translation", "> 0 m");
  require(sigma_rotation > 0.0, "loop_correction.sigma_rotation", "> 0 rad");
  graph.validate();
}

LoopCorrectionResult correct_loops(Map& map, const std::vector<LoopConstraint>& loops,
                                   const LoopCorrectionOptions& options) {
  options.validate();
  const std::vector<KeyframeId> ids = map.keyframe_ids();
  std::map<KeyframeId, std::size_t> node_of;
  std::vector<Eigen::Isometry3d> T_world_node;
  T_world_node.reserve(ids.size());
  for (const KeyframeId id : ids) {
    node_of.emplace(id, T_world_node.size());
    T_world_node.push_back(map.keyframe(id)->T_cam_world.inverse());
  }
  for (std::size_t i = 0; i < loops.size(); ++i) {
    if (node_of.count(loops[i].current) == 0 || node_of.count(loops[i].matched) == 0) {
      throw ConfigError(fmt::format("loops[{}]", i), fmt::format("keyframes the map holds (has {} -> {})",
                                                                 loops[i].current.value, loops[i].matched.value));
    }
  }

  std::vector<PoseGraphEdge> edges;
  std::set<std::pair<std::size_t, std::size_t>> joined;  // unordered pairs already in the graph
  const auto add_measured_edge = [&](std::size_t a, std::size_t b) {
    if (!joined.insert(std::minmax(a, b)).second) return;
    PoseGraphEdge e;
    e.from = a;
    e.to = b;
    e.T_from_to = T_world_node[a].inverse() * T_world_node[b];  // the map's own relative pose
    e.sigma_translation = options.sigma_translation;
    e.sigma_rotation = options.sigma_rotation;
    edges.push_back(e);
  };
  std::vector<std::size_t> fixed;
  for (const KeyframeId id : ids) {
    const Keyframe& k = *map.keyframe(id);
    const std::size_t node = node_of.at(id);
    const auto parent = node_of.find(k.parent);
    if (parent != node_of.end()) {
      add_measured_edge(parent->second, node);
    } else {
      fixed.push_back(node);  // a root: holds the gauge of its part of the map
    }
    for (const auto& [other, weight] : k.covisibility) {
      const auto it = node_of.find(other);
      if (weight >= options.min_covisibility && it != node_of.end()) add_measured_edge(node, it->second);
    }
  }
  const std::size_t first_loop_edge = edges.size();
  for (const LoopConstraint& loop : loops) {
    PoseGraphEdge e;
    e.from = node_of.at(loop.current);
    e.to = node_of.at(loop.matched);
    e.T_from_to = loop.T_current_matched;
    e.sigma_translation = options.sigma_translation;
    e.sigma_rotation = options.sigma_rotation;
    edges.push_back(e);
  }
  LoopCorrectionResult result;
  result.keyframes = ids.size();
  result.edges = edges.size();
  if (ids.empty()) return result;
  if (fixed.empty()) fixed.push_back(0);

  const auto loop_error = [&](const std::vector<Eigen::Isometry3d>& poses) {
    double worst = 0.0;
    for (std::size_t i = first_loop_edge; i < edges.size(); ++i) {
      const PoseGraphEdge& e = edges[i];
      const Eigen::Isometry3d E = e.T_from_to.inverse() * poses[e.from].inverse() * poses[e.to];
      worst = std::max(worst, E.translation().norm());
    }
    return worst;
  };
  result.loop_error_before_m = loop_error(T_world_node);

  const PoseGraphResult solved = optimize_pose_graph(T_world_node, edges, fixed, options.graph);
  result.converged = solved.converged;
  result.loop_error_after_m = loop_error(solved.T_world_node);

  // Landmarks ride with their reference keyframe: p' = T_world_ref' * T_ref_world * p.
  std::vector<Eigen::Isometry3d> correction(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    correction[i] = solved.T_world_node[i] * T_world_node[i].inverse();
    result.max_keyframe_shift_m =
        std::max(result.max_keyframe_shift_m,
                 (solved.T_world_node[i].translation() - T_world_node[i].translation()).norm());
  }
  for (const LandmarkId lid : map.landmark_ids()) {
    Landmark* l = map.landmark(lid);
    const auto it = node_of.find(l->reference_keyframe);
    if (it == node_of.end()) continue;
    l->position = correction[it->second] * l->position;
    ++result.landmarks;
  }
  for (std::size_t i = 0; i < ids.size(); ++i) map.keyframe(ids[i])->T_cam_world = solved.T_world_node[i].inverse();
  // normals and distance ranges follow the new geometry
  for (const LandmarkId lid : map.landmark_ids()) map.update_landmark(lid);
  return result;
}

}  // namespace rgbl
