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
#include <utility>
#include <vector>

namespace rgbl {
namespace {

struct PointMatch {
  int keypoint = 0;
  Eigen::Vector3d p_cam;    // current keyframe's camera frame, from its depth
  Eigen::Vector3d p_world;  // the landmark, in the candidate's map
};

// Where a loop is looked for: the landmarks of the candidate and of its best covisible keyframes.
std::vector<LandmarkId> region_landmarks(const Map& map, KeyframeId candidate, std::size_t neighbours) {
  return map.landmarks_seen_by(map.neighbourhood(candidate, neighbours));
}

// What one verification works on: the current keyframe against the candidate's region.
struct Search {
  const PinholeCamera& camera;
  const Keyframe& current;
  const Map& map;
  const Keyframe& matched;
  const LoopVerificationOptions& options;
  std::vector<LandmarkId> landmarks;  // region_landmarks of `matched`
};

// How close (m) a point at `depth` must come to agree in 3-D.
double tolerance(double depth, const LoopVerificationOptions& o) {
  return std::max(o.min_tolerance, o.relative_tolerance * depth);
}

// Ratio test against the nearest landmark *elsewhere*: the second best is the closest descriptor among
// landmarks beyond the 3-D agreement tolerance of the best one. Keyframes whose landmarks were never
// fused leave one point in the region twice, centimetres apart with nearly equal descriptors; those
// copies are no ambiguity (either fixes the same pose), while the copies of a repeated facade, metres
// apart, still are.
std::vector<PointMatch> match_descriptors(const Search& s) {
  const Keyframe& current = s.current;
  std::vector<const Landmark*> landmarks;
  landmarks.reserve(s.landmarks.size());
  for (const LandmarkId id : s.landmarks) landmarks.push_back(s.map.landmark(id));
  std::vector<int> distance(landmarks.size());
  // landmark -> (keypoint, distance): each landmark keeps its best keypoint
  std::map<int, std::pair<int, int>> best_of_landmark;
  for (std::size_t i = 0; i < current.keypoints.size(); ++i) {
    if (current.depth[i] <= 0.0F) continue;
    int best = 256;
    std::size_t best_j = landmarks.size();
    for (std::size_t j = 0; j < landmarks.size(); ++j) {
      distance[j] = hamming_distance(current.descriptors[i], landmarks[j]->descriptor);
      if (distance[j] < best) {
        best = distance[j];
        best_j = j;
      }
    }
    if (best_j == landmarks.size() || best > s.options.max_hamming) continue;
    const double elsewhere = tolerance(current.depth[i], s.options);
    const Eigen::Vector3d& at = landmarks[best_j]->position;
    bool ambiguous = false;
    for (std::size_t j = 0; j < landmarks.size() && !ambiguous; ++j) {
      ambiguous = j != best_j && static_cast<float>(best) >= s.options.ratio * static_cast<float>(distance[j]) &&
                  (landmarks[j]->position - at).norm() > elsewhere;
    }
    if (ambiguous) continue;
    const int best_id = s.landmarks[best_j].value;
    const auto it = best_of_landmark.find(best_id);
    if (it == best_of_landmark.end() || best < it->second.second) {
      best_of_landmark[best_id] = {static_cast<int>(i), best};
    }
  }
  std::vector<PointMatch> matches;
  matches.reserve(best_of_landmark.size());
  for (const auto& [landmark, kp] : best_of_landmark) {
    const auto k = static_cast<std::size_t>(kp.first);
    PointMatch m;
    m.keypoint = kp.first;
    m.p_cam = s.camera.unproject(Eigen::Vector2d(current.keypoints[k].x, current.keypoints[k].y), current.depth[k]);
    m.p_world = s.map.landmark(LandmarkId{landmark})->position;
    matches.push_back(m);
  }
  return matches;
}

double tolerance(const PointMatch& m, const LoopVerificationOptions& o) { return tolerance(m.p_cam.z(), o); }

bool agrees(const PointMatch& m, const Eigen::Isometry3d& T_cam_world, const LoopVerificationOptions& options) {
  return (T_cam_world * m.p_world - m.p_cam).norm() < tolerance(m, options);
}

int count_agreeing(const std::vector<PointMatch>& matches, const Eigen::Isometry3d& T_cam_world,
                   const LoopVerificationOptions& options) {
  return static_cast<int>(
      std::count_if(matches.begin(), matches.end(), [&](const PointMatch& m) { return agrees(m, T_cam_world, options); }));
}

std::vector<std::size_t> agreeing(const std::vector<PointMatch>& matches, const Eigen::Isometry3d& T_cam_world,
                                  const LoopVerificationOptions& options) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (agrees(matches[i], T_cam_world, options)) out.push_back(i);
  }
  return out;
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
PoseOptimizerResult refine(const Search& s, const std::vector<PointMatch>& matches, const Eigen::Isometry3d& T_cam_world) {
  const Keyframe& current = s.current;
  std::vector<PoseObservation> observations;
  observations.reserve(matches.size());
  for (const PointMatch& m : matches) {
    const auto k = static_cast<std::size_t>(m.keypoint);
    PoseObservation o;
    o.p_world = m.p_world;
    o.pixel = Eigen::Vector2d(current.keypoints[k].x, current.keypoints[k].y);
    o.sigma_px = std::pow(s.map.options().scale_factor, current.keypoints[k].level);
    o.depth = current.depth[k];
    o.depth_sigma = k < current.depth_sigma.size() && current.depth_sigma[k] > 0.0F ? current.depth_sigma[k]
                                                                                      : tolerance(m, s.options);
    observations.push_back(o);
  }
  return optimize_pose(s.camera, T_cam_world, observations);
}

// Region landmarks seen from T_cam_world, each searched near its projection (no ratio test, any
// pyramid level, radius guided_radius_px times the scale of the level its distance predicts); each
// keypoint keeps its closest landmark. Keypoints without depth join by reprojection alone.
std::vector<PointMatch> guided_search(const Search& s, const FeatureGrid& grid, const Eigen::Isometry3d& T_cam_world) {
  const MapOptions& map_options = s.map.options();
  const Eigen::Vector3d center = T_cam_world.inverse().translation();
  std::vector<GuidedQuery> queries;
  std::vector<LandmarkId> landmark_of_query;
  queries.reserve(s.landmarks.size());
  landmark_of_query.reserve(s.landmarks.size());
  for (const LandmarkId id : s.landmarks) {
    const Landmark& landmark = *s.map.landmark(id);
    const Eigen::Vector3d p_cam = T_cam_world * landmark.position;
    if (p_cam.z() <= 0.0) continue;
    const auto px = s.camera.project(p_cam);
    if (!px || !s.camera.in_image(*px)) continue;
    GuidedQuery q;
    q.x = static_cast<float>(px->x());
    q.y = static_cast<float>(px->y());
    q.level = landmark.predict_level((landmark.position - center).norm(), map_options.levels, map_options.scale_factor);
    q.descriptor = &landmark.descriptor;
    queries.push_back(q);
    landmark_of_query.push_back(id);
  }
  GuidedMatchOptions guided;
  guided.radius = static_cast<float>(s.options.guided_radius_px);
  guided.scale_factor = static_cast<float>(map_options.scale_factor);
  guided.level_window = map_options.levels;
  guided.max_distance = s.options.max_hamming;
  guided.ratio = 1.0F;
  guided.check_orientation = false;
  const Keyframe& current = s.current;
  const std::vector<int> keypoint_of_query = match_guided(queries, grid, current.keypoints, current.descriptors, guided);
  std::vector<PointMatch> matches;
  for (std::size_t q = 0; q < queries.size(); ++q) {
    if (keypoint_of_query[q] < 0) continue;
    const auto k = static_cast<std::size_t>(keypoint_of_query[q]);
    PointMatch m;
    m.keypoint = keypoint_of_query[q];
    m.p_cam = current.depth[k] > 0.0F ? s.camera.unproject(Eigen::Vector2d(current.keypoints[k].x, current.keypoints[k].y),
                                                           current.depth[k])
                                      : Eigen::Vector3d::Zero();
    m.p_world = s.map.landmark(landmark_of_query[q])->position;
    matches.push_back(m);
  }
  return matches;
}

// The common end of both verifications: the pose is refined from T_cam_world on `matches` (needs
// min_ransac_inliers inliers), every region landmark is searched from the refined pose, and the pose
// refined on those guided matches is accepted with enough inliers, absolutely and as a share of them.
std::optional<LoopVerification> refine_search_accept(const Search& s, const FeatureGrid& grid,
                                                     const std::vector<PointMatch>& matches,
                                                     const Eigen::Isometry3d& T_cam_world, LoopVerificationCounts& reached) {
  const PoseOptimizerResult first = refine(s, matches, T_cam_world);
  if (first.inliers < s.options.min_ransac_inliers) {
    reached.inliers = first.inliers;
    return std::nullopt;
  }
  const std::vector<PointMatch> guided = guided_search(s, grid, first.T_cam_world);
  reached.guided_matches = static_cast<int>(guided.size());
  const PoseOptimizerResult refined = refine(s, guided, first.T_cam_world);
  reached.inliers = refined.inliers;
  if (reached.inliers < s.options.min_inliers ||
      reached.inliers < s.options.min_inlier_ratio * static_cast<double>(guided.size())) {
    return std::nullopt;
  }
  LoopVerification v;
  v.counts = reached;
  v.T_cam_world = refined.T_cam_world;
  v.constraint.current = s.current.id;
  v.constraint.matched = s.matched.id;
  v.constraint.T_current_matched = refined.T_cam_world * s.matched.T_cam_world.inverse();
  return v;
}

// 3-point RANSAC on the 3-D pairs, refitted on its consensus: the motion and the indices of the
// matches that agree with it, or nullopt below min_ransac_inliers (counts.ransac_inliers says how many).
// Own index draws (rng() % n), so the samples are the same with every standard library.
std::optional<std::pair<Eigen::Isometry3d, std::vector<std::size_t>>> ransac_consensus(
    const std::vector<PointMatch>& matches, const LoopVerificationOptions& options, LoopVerificationCounts& counts) {
  counts.ransac_inliers = 0;
  if (std::cmp_less(matches.size(), options.min_ransac_inliers)) return std::nullopt;
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
  counts.ransac_inliers = best_count;
  if (best_count < options.min_ransac_inliers) return std::nullopt;
  best_T = align(matches, agreeing(matches, best_T, options));  // refit on the consensus
  std::vector<std::size_t> consensus = agreeing(matches, best_T, options);
  counts.ransac_inliers = static_cast<int>(consensus.size());
  if (counts.ransac_inliers < options.min_ransac_inliers) return std::nullopt;
  return std::make_pair(best_T, std::move(consensus));
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
  require(max_motions >= 1, "loop_verification.max_motions", ">= 1");
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
  const Search search{camera, current, map, *matched, options, region_landmarks(map, candidate, options.neighbours)};
  const std::vector<PointMatch> matches = match_descriptors(search);
  reached.matches = static_cast<int>(matches.size());
  if (reached.matches < options.min_ransac_inliers) return std::nullopt;

  // The best rigid motion of the matches, then the best of those it leaves out, up to max_motions: a
  // car driving ahead (or any object moving as one) is a rigid motion of its own, and where its points
  // are in the map (seen once and not culled) it can outnumber the street's among the descriptor
  // matches. Each motion with min_ransac_inliers is refined and searched; the one that explains most
  // of the region wins. (04's revisit test with the ring plane fit and without the first keyframe's
  // culling: 86 RANSAC inliers on the car ahead, its pose 5.3 m off with 109 inliers after the search;
  // the street's motion, second, 76 and 152, 2026-12-05.)
  const FeatureGrid grid(current.keypoints, camera.width, camera.height);
  std::vector<bool> taken(matches.size(), false);
  std::optional<LoopVerification> best;
  LoopVerificationCounts best_counts;
  for (int motion = 0; motion < options.max_motions; ++motion) {
    std::vector<PointMatch> rest;
    std::vector<std::size_t> index_of_rest;  // into matches
    for (std::size_t i = 0; i < matches.size(); ++i) {
      if (taken[i]) continue;
      rest.push_back(matches[i]);
      index_of_rest.push_back(i);
    }
    LoopVerificationCounts got = reached;
    const auto consensus = ransac_consensus(rest, options, got);
    if (!consensus) {
      if (motion == 0) reached = got;
      break;
    }
    // Refined on the consensus alone first: a gross outlier close to the camera (a landmark a metre in
    // front of it) has a huge reprojection Jacobian and drags an undamped Gauss-Newton step away from
    // a good start. The guided search from the refined pose then brings in many more matches than the
    // ratio test lets through, and the pose is fixed by them rather than by a few dozen.
    std::vector<PointMatch> consensus_matches;
    consensus_matches.reserve(consensus->second.size());
    for (const std::size_t i : consensus->second) {
      consensus_matches.push_back(rest[i]);
      taken[index_of_rest[i]] = true;  // left out of the next motion's search
    }
    auto verified = refine_search_accept(search, grid, consensus_matches, consensus->first, got);
    if (motion == 0) reached = got;
    if (verified && (!best || verified->counts.inliers > best->counts.inliers)) {
      best = std::move(verified);
      best_counts = got;
    }
  }
  if (best) reached = best_counts;
  return best;
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
  const Search search{camera, current, map, *matched, options, region_landmarks(map, candidate, options.neighbours)};
  const FeatureGrid grid(current.keypoints, camera.width, camera.height);
  // The guess is the loop's prediction, a little off: a first search from it needs as many matches as
  // RANSAC must find in verify_loop; the refined pose is searched from again, which finds the landmarks
  // that fell outside the radius the first time, and the decision is on that second search.
  const std::vector<PointMatch> matches = guided_search(search, grid, T_cam_world_guess);
  reached.matches = static_cast<int>(matches.size());
  if (reached.matches < options.min_ransac_inliers) return std::nullopt;
  return refine_search_accept(search, grid, matches, T_cam_world_guess, reached);
}

}  // namespace rgbl
