#include "rgbl/loop/verification.hpp"

#include "rgbl/backend/pose_optimizer.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/features/matcher.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

namespace rgbl {
namespace {

struct PointMatch {
  int keypoint = 0;
  Eigen::Vector3d p_cam;    // current keyframe's camera frame, from its depth
  Eigen::Vector3d p_world;  // the landmark, in the candidate's map
};

std::vector<PointMatch> match_descriptors(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                     const std::vector<LandmarkId>& landmarks, const LoopVerificationOptions& options) {
  // landmark -> (keypoint, distance): each landmark keeps its best keypoint
  std::map<int, std::pair<int, int>> best_of_landmark;
  for (std::size_t i = 0; i < current.keypoints.size(); ++i) {
    if (current.depth[i] <= 0.0F) continue;
    int best = 256, second = 256;
    LandmarkId best_id;
    for (const LandmarkId id : landmarks) {
      const int d = hamming_distance(current.descriptors[i], map.landmark(id)->descriptor);
      if (d < best) {
        second = best;
        best = d;
        best_id = id;
      } else if (d < second) {
        second = d;
      }
    }
    if (!best_id.valid() || best > options.max_hamming || static_cast<float>(best) >= options.ratio * static_cast<float>(second)) {
      continue;
    }
    const auto it = best_of_landmark.find(best_id.value);
    if (it == best_of_landmark.end() || best < it->second.second) {
      best_of_landmark[best_id.value] = {static_cast<int>(i), best};
    }
  }
  std::vector<PointMatch> matches;
  matches.reserve(best_of_landmark.size());
  for (const auto& [landmark, kp] : best_of_landmark) {
    const auto k = static_cast<std::size_t>(kp.first);
    PointMatch m;
    m.keypoint = kp.first;
    m.p_cam = camera.unproject(Eigen::Vector2d(current.keypoints[k].x, current.keypoints[k].y), current.depth[k]);
    m.p_world = map.landmark(LandmarkId{landmark})->position;
    matches.push_back(m);
  }
  return matches;
}

double tolerance(const PointMatch& m, const LoopVerificationOptions& o) {
  return std::max(o.min_tolerance, o.relative_tolerance * m.p_cam.z());
}

int count_agreeing(const std::vector<PointMatch>& matches, const Eigen::Isometry3d& T_cam_world,
                   const LoopVerificationOptions& options, std::vector<char>* agree = nullptr) {
  int n = 0;
  if (agree != nullptr) agree->assign(matches.size(), 0);
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if ((T_cam_world * matches[i].p_world - matches[i].p_cam).norm() < tolerance(matches[i], options)) {
      ++n;
      if (agree != nullptr) (*agree)[i] = 1;
    }
  }
  return n;
}

// Rigid T_cam_world from matched pairs (Umeyama without scale).
Eigen::Isometry3d align(const std::vector<PointMatch>& matches, const std::vector<std::size_t>& use) {
  Eigen::Matrix3Xd world(3, static_cast<Eigen::Index>(use.size())), cam(3, static_cast<Eigen::Index>(use.size()));
  for (std::size_t k = 0; k < use.size(); ++k) {
    world.col(static_cast<Eigen::Index>(k)) = matches[use[k]].p_world;
    cam.col(static_cast<Eigen::Index>(k)) = matches[use[k]].p_cam;
  }
  Eigen::Isometry3d T;
  T.matrix() = Eigen::umeyama(world, cam, false);
  return T;
}

// Refine on reprojection (and depth where the keypoint has it) of every match; the optimiser
// re-classifies outliers.
PoseOptimizerResult refine(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                           const std::vector<PointMatch>& matches, const Eigen::Isometry3d& T_cam_world,
                           const LoopVerificationOptions& options) {
  std::vector<PoseObservation> observations;
  observations.reserve(matches.size());
  for (const PointMatch& m : matches) {
    const auto k = static_cast<std::size_t>(m.keypoint);
    PoseObservation o;
    o.p_world = m.p_world;
    o.pixel = Eigen::Vector2d(current.keypoints[k].x, current.keypoints[k].y);
    o.sigma_px = std::pow(map.options().scale_factor, current.keypoints[k].level);
    o.depth = current.depth[k];
    o.depth_sigma = k < current.depth_sigma.size() && current.depth_sigma[k] > 0.0F ? current.depth_sigma[k]
                                                                                      : tolerance(m, options);
    observations.push_back(o);
  }
  return optimize_pose(camera, T_cam_world, observations);
}

// Refines the pose from T_cam_world and accepts it with enough inliers, absolutely and as a share of
// the matches; fills reached.inliers either way.
std::optional<LoopVerification> refine_and_accept(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                                  const Keyframe& matched, const std::vector<PointMatch>& matches,
                                                  const Eigen::Isometry3d& T_cam_world,
                                                  const LoopVerificationOptions& options, LoopVerificationCounts& reached) {
  const PoseOptimizerResult refined = refine(camera, current, map, matches, T_cam_world, options);
  reached.inliers = refined.inliers;
  if (reached.inliers < options.min_inliers ||
      reached.inliers < options.min_inlier_ratio * static_cast<double>(matches.size())) {
    return std::nullopt;
  }
  LoopVerification v;
  v.counts = reached;
  v.T_cam_world = refined.T_cam_world;
  v.constraint.current = current.id;
  v.constraint.matched = matched.id;
  v.constraint.T_current_matched = refined.T_cam_world * matched.T_cam_world.inverse();
  return v;
}

// Where a loop is looked for: the landmarks of the candidate and of its best covisible keyframes.
std::vector<LandmarkId> region_landmarks(const Map& map, KeyframeId candidate, std::size_t neighbours) {
  std::vector<KeyframeId> around{candidate};
  for (const KeyframeId id : map.best_covisible(candidate, neighbours)) around.push_back(id);
  return map.landmarks_seen_by(around);
}

// Landmarks seen from T_cam_world, each searched near its projection (no ratio test, any pyramid
// level, radius guided_radius_px times the scale of the level its distance predicts); each keypoint
// keeps its closest landmark. Keypoints without depth join by reprojection alone.
std::vector<PointMatch> guided_search(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                      const std::vector<LandmarkId>& landmarks, const Eigen::Isometry3d& T_cam_world,
                                      const LoopVerificationOptions& options) {
  const Eigen::Vector3d center = T_cam_world.inverse().translation();
  std::vector<GuidedQuery> queries;
  std::vector<LandmarkId> landmark_of_query;
  queries.reserve(landmarks.size());
  landmark_of_query.reserve(landmarks.size());
  for (const LandmarkId id : landmarks) {
    const Landmark& landmark = *map.landmark(id);
    const Eigen::Vector3d p_cam = T_cam_world * landmark.position;
    if (p_cam.z() <= 0.0) continue;
    const auto px = camera.project(p_cam);
    if (!px || !camera.in_image(*px)) continue;
    GuidedQuery q;
    q.x = static_cast<float>(px->x());
    q.y = static_cast<float>(px->y());
    q.level = landmark.predict_level((landmark.position - center).norm(), map.options().levels,
                                     map.options().scale_factor);
    q.descriptor = &landmark.descriptor;
    queries.push_back(q);
    landmark_of_query.push_back(id);
  }
  GuidedMatchOptions guided;
  guided.radius = static_cast<float>(options.guided_radius_px);
  guided.scale_factor = static_cast<float>(map.options().scale_factor);
  guided.level_window = map.options().levels;
  guided.max_distance = options.max_hamming;
  guided.ratio = 1.0F;
  guided.check_orientation = false;
  const FeatureGrid grid(current.keypoints, camera.width, camera.height);
  const std::vector<int> keypoint_of_query = match_guided(queries, grid, current.keypoints, current.descriptors, guided);
  std::vector<PointMatch> matches;
  for (std::size_t q = 0; q < queries.size(); ++q) {
    if (keypoint_of_query[q] < 0) continue;
    const auto k = static_cast<std::size_t>(keypoint_of_query[q]);
    PointMatch m;
    m.keypoint = keypoint_of_query[q];
    m.p_cam = current.depth[k] > 0.0F
                  ? camera.unproject(Eigen::Vector2d(current.keypoints[k].x, current.keypoints[k].y), current.depth[k])
                  : Eigen::Vector3d::Zero();
    m.p_world = map.landmark(landmark_of_query[q])->position;
    matches.push_back(m);
  }
  return matches;
}

// Options valid and one descriptor and one depth per keypoint, else ConfigError.
void check(const LoopVerificationOptions& options, const Keyframe& current) {
  options.validate();
  if (current.descriptors.size() != current.keypoints.size() || current.depth.size() != current.keypoints.size()) {
    throw ConfigError("current keyframe", fmt::format("one descriptor and one depth per keypoint (has {} keypoints, {} "
                                                      "descriptors, {} depths)",
                                                      current.keypoints.size(), current.descriptors.size(),
                                                      current.depth.size()));
  }
}

}  // namespace

void LoopVerificationOptions::validate() const {
  require(max_hamming >= 0 && max_hamming <= 256, "loop_verification.max_hamming", "0..256");
  require(ratio > 0.0F && ratio <= 1.0F, "loop_verification.ratio", "in (0, 1]");
  require(ransac_iterations >= 1, "loop_verification.ransac_iterations", ">= 1");
  require(min_tolerance > 0.0 && relative_tolerance >= 0.0, "loop_verification.tolerance",
          "min_tolerance > 0 m and relative_tolerance >= 0");
  require(min_ransac_inliers >= 3, "loop_verification.min_ransac_inliers", ">= 3");
  require(min_inliers >= 3, "loop_verification.min_inliers", ">= 3");
  require(guided_radius_px > 0.0, "loop_verification.guided_radius_px", "> 0 px");
  require(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0, "loop_verification.min_inlier_ratio", "in [0, 1]");
}

std::optional<LoopVerification> verify_loop(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                            KeyframeId candidate, const LoopVerificationOptions& options,
                                            LoopVerificationCounts* counts) {
  check(options, current);
  LoopVerificationCounts scratch;
  LoopVerificationCounts& reached = counts != nullptr ? *counts : scratch;
  reached = {};
  const Keyframe* matched = map.keyframe(candidate);
  if (matched == nullptr) return std::nullopt;
  const std::vector<LandmarkId> landmarks = region_landmarks(map, candidate, options.neighbours);
  const std::vector<PointMatch> matches = match_descriptors(camera, current, map, landmarks, options);
  reached.matches = static_cast<int>(matches.size());
  if (reached.matches < options.min_ransac_inliers) return std::nullopt;

  // 3-point RANSAC on the 3-D pairs; own index draws (rng() % n), so the samples are the same with
  // every standard library.
  std::mt19937 rng(options.seed);
  const std::size_t n = matches.size();
  Eigen::Isometry3d best_T = Eigen::Isometry3d::Identity();
  int best_count = 0;
  for (int it = 0; it < options.ransac_iterations; ++it) {
    const std::size_t a = rng() % n, b = rng() % n, c = rng() % n;
    if (a == b || b == c || a == c) continue;
    const Eigen::Vector3d& pa = matches[a].p_world;
    // nearly colinear or tiny samples fix no rotation
    if ((matches[b].p_world - pa).cross(matches[c].p_world - pa).norm() < 0.5) continue;
    const Eigen::Isometry3d T = align(matches, {a, b, c});
    const int count = count_agreeing(matches, T, options);
    if (count > best_count) {
      best_count = count;
      best_T = T;
    }
  }
  reached.ransac_inliers = best_count;
  if (best_count < options.min_ransac_inliers) return std::nullopt;
  std::vector<char> agree;
  count_agreeing(matches, best_T, options, &agree);
  std::vector<std::size_t> consensus;
  for (std::size_t i = 0; i < n; ++i) {
    if (agree[i] != 0) consensus.push_back(i);
  }
  best_T = align(matches, consensus);
  std::vector<PointMatch> agreeing;
  for (std::size_t i = 0; i < n; ++i) {
    if ((best_T * matches[i].p_world - matches[i].p_cam).norm() < tolerance(matches[i], options)) {
      agreeing.push_back(matches[i]);
    }
  }
  reached.ransac_inliers = static_cast<int>(agreeing.size());
  if (reached.ransac_inliers < options.min_ransac_inliers) return std::nullopt;

  // Refine on the consensus alone first: a gross outlier close to the camera (a landmark a metre in
  // front of it) has a huge reprojection Jacobian and drags an undamped Gauss-Newton step away from a
  // good start. Then every region landmark is searched near where the refined pose projects it: many
  // more matches than the ratio test lets through, and a pose fixed by them rather than by a few dozen.
  const PoseOptimizerResult first = refine(camera, current, map, agreeing, best_T, options);
  if (first.inliers < options.min_ransac_inliers) {
    reached.inliers = first.inliers;
    return std::nullopt;
  }
  const std::vector<PointMatch> guided = guided_search(camera, current, map, landmarks, first.T_cam_world, options);
  reached.guided_matches = static_cast<int>(guided.size());
  return refine_and_accept(camera, current, map, *matched, guided, first.T_cam_world, options, reached);
}

std::optional<LoopVerification> verify_loop_guided(const PinholeCamera& camera, const Keyframe& current, const Map& map,
                                                   KeyframeId candidate, const Eigen::Isometry3d& T_cam_world_guess,
                                                   const LoopVerificationOptions& options,
                                                   LoopVerificationCounts* counts) {
  check(options, current);
  LoopVerificationCounts scratch;
  LoopVerificationCounts& reached = counts != nullptr ? *counts : scratch;
  reached = {};
  const Keyframe* matched = map.keyframe(candidate);
  if (matched == nullptr) return std::nullopt;
  const std::vector<LandmarkId> landmarks = region_landmarks(map, candidate, options.neighbours);
  std::vector<PointMatch> matches = guided_search(camera, current, map, landmarks, T_cam_world_guess, options);
  reached.matches = static_cast<int>(matches.size());
  // The guess is the loop's prediction, a little off: refine it on what the first search found (as
  // much as RANSAC must find in verify_loop) and search again from the refined pose, which finds the
  // landmarks that fell outside the radius the first time. The decision is on the second search.
  if (reached.matches < options.min_ransac_inliers) return std::nullopt;
  const PoseOptimizerResult first = refine(camera, current, map, matches, T_cam_world_guess, options);
  if (first.inliers < options.min_ransac_inliers) {
    reached.inliers = first.inliers;
    return std::nullopt;
  }
  matches = guided_search(camera, current, map, landmarks, first.T_cam_world, options);
  reached.guided_matches = static_cast<int>(matches.size());
  return refine_and_accept(camera, current, map, *matched, matches, first.T_cam_world, options, reached);
}

}  // namespace rgbl
