#include "rgbl/tracking/frame_motion.hpp"

#include "matching.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/geometry/epipolar.hpp"
#include "rgbl/geometry/voxel_index.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <iterator>
#include <optional>
#include <tuple>
#include <vector>

namespace rgbl {

namespace {

// A depth error lies along the viewing ray; the road is seen at a grazing angle, so only the ray's
// component along the plane normal moves a point off the plane (its depth error times n.p/|p|).
double ground_tolerance(const Eigen::Vector3d& p, const Eigen::Vector3d& n, const TrackerOptions& options) {
  return std::max(options.ground_tolerance, options.ransac_relative_tolerance * p.z() * std::abs(n.dot(p)) / p.norm());
}

struct GroundPlane {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();  // pointing down, as the camera's y
  double d = 0.0;                               // the camera's height above it
};

// The fixed-seed RANSAC of ground_points over the candidate points `below`.
std::optional<GroundPlane> fit_ground(std::span<const Eigen::Vector3d> points, std::span<const int> below,
                                      const TrackerOptions& options) {
  if (static_cast<int>(below.size()) < options.ground_min_points) return std::nullopt;
  const double cos_tilt = std::cos(options.ground_max_tilt_deg * std::numbers::pi / 180.0);
  std::mt19937 rng(11);  // fixed seed: deterministic
  std::uniform_int_distribution<std::size_t> pick(0, below.size() - 1);
  int best_count = 0;
  GroundPlane best;
  for (int it = 0; it < options.ground_iterations; ++it) {
    const Eigen::Vector3d& a = points[static_cast<std::size_t>(below[pick(rng)])];
    const Eigen::Vector3d& b = points[static_cast<std::size_t>(below[pick(rng)])];
    const Eigen::Vector3d& c = points[static_cast<std::size_t>(below[pick(rng)])];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-6) continue;
    n.normalize();
    if (n.y() < 0.0) n = -n;
    if (n.y() < cos_tilt) continue;
    const double d = n.dot(a);
    if (d < options.ground_min_height) continue;
    int count = 0;
    for (const int i : below) {
      const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
      count += std::abs(n.dot(p) - d) < ground_tolerance(p, n, options) ? 1 : 0;
    }
    if (count > best_count) {
      best_count = count;
      best = {n, d};
    }
  }
  if (best_count < options.ground_min_points) return std::nullopt;
  return best;
}

std::vector<int> below_camera(std::span<const Eigen::Vector3d> points, const TrackerOptions& options) {
  std::vector<int> below;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    if (points[static_cast<std::size_t>(i)].y() >= options.ground_min_height) below.push_back(i);
  }
  return below;
}

// Flags the points of `below` on the plane.
std::vector<bool> on_ground(std::span<const Eigen::Vector3d> points, std::span<const int> below,
                            const GroundPlane& plane, const TrackerOptions& options) {
  std::vector<bool> ground(points.size(), false);
  for (const int i : below) {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
    ground[static_cast<std::size_t>(i)] = std::abs(plane.n.dot(p) - plane.d) < ground_tolerance(p, plane.n, options);
  }
  return ground;
}

}  // namespace

std::vector<bool> ground_points(std::span<const Eigen::Vector3d> points, const TrackerOptions& options) {
  const std::vector<int> below = below_camera(points, options);
  const std::optional<GroundPlane> plane = fit_ground(points, below, options);
  return plane ? on_ground(points, below, *plane, options) : std::vector<bool>{};
}

namespace {

// A scan sample's ground: its returns as doubles, those below the camera, and the plane with the
// returns on it (`ground` empty without a plane). The plane is fitted on at most 2000 of the returns
// below the camera (a scan holds ten times more than the road needs), and every one is then judged
// against it.
struct ScanGround {
  std::vector<Eigen::Vector3d> points;
  std::vector<int> below;
  std::optional<GroundPlane> plane;
  std::vector<bool> ground;
};

ScanGround scan_ground(const ScanSample& sample, const TrackerOptions& options) {
  ScanGround g;
  g.points.resize(sample.points.size());
  for (std::size_t i = 0; i < g.points.size(); ++i) g.points[i] = sample.points[i].cast<double>();
  g.below = below_camera(g.points, options);
  std::vector<int> fit_on;
  const std::size_t stride = g.below.size() / 2000 + 1;
  for (std::size_t k = 0; k < g.below.size(); k += stride) fit_on.push_back(g.below[k]);
  g.plane = fit_ground(g.points, fit_on, options);
  if (g.plane) g.ground = on_ground(g.points, g.below, *g.plane, options);
  return g;
}

}  // namespace

ScanSample scan_evidence(const ScanSample& sample, const TrackerOptions& options) {
  const ScanGround g = scan_ground(sample, options);
  const std::vector<Eigen::Vector3d>& points = g.points;
  const std::vector<bool>& ground = g.ground;
  ScanSample evidence;
  VoxelIndex taken;
  taken.reserve(sample.points.size());
  const auto inv = static_cast<float>(1.0 / options.scan_sample.tolerance);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!ground.empty() && ground[i]) continue;
    if (taken.emplace(voxel_of(sample.points[i], inv), 0).second) evidence.points.push_back(sample.points[i]);
  }
  return evidence;
}

std::optional<RoadPlane> road_plane(const ScanSample& sample, const TrackerOptions& options) {
  const ScanGround g = scan_ground(sample, options);
  if (!g.plane) return std::nullopt;
  // least squares over every return on it: the plane through their centroid across their least spread
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int count = 0;
  for (const int i : g.below) {
    if (!g.ground[static_cast<std::size_t>(i)]) continue;
    mean += g.points[static_cast<std::size_t>(i)];
    ++count;
  }
  if (count < options.ground_min_points) return std::nullopt;
  mean /= count;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const int i : g.below) {
    if (!g.ground[static_cast<std::size_t>(i)]) continue;
    const Eigen::Vector3d q = g.points[static_cast<std::size_t>(i)] - mean;
    scatter += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  Eigen::Vector3d n = solver.eigenvectors().col(0);  // the smallest eigenvalue's
  if (n.y() < 0.0) n = -n;
  RoadPlane road;
  road.n = n;
  road.d = n.dot(mean);
  road.points = count;
  return road;
}

std::vector<bool> ground_keypoints(const PinholeCamera& camera, const Frame& frame, const TrackerOptions& options) {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::size_t> keypoint;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.depth_sigma[i] <= 0.0F) continue;
    points.push_back(camera.unproject(Eigen::Vector2d(frame.keypoints[i].x, frame.keypoints[i].y), frame.depth[i]));
    keypoint.push_back(i);
  }
  const std::vector<bool> on_plane = ground_points(points, options);
  if (on_plane.empty()) return {};
  std::vector<bool> ground(frame.size(), false);
  for (std::size_t k = 0; k < keypoint.size(); ++k) ground[keypoint[k]] = on_plane[k];
  return ground;
}

// A rival motion needs no more than a minimal sample's support: the local map judges it (tracker).
constexpr int kMinRivalInliers = 3;

namespace {

// The stride that keeps at most max_points of `with_depth` keypoints (1: every one).
std::size_t subset_stride(std::size_t with_depth, std::size_t max_points) {
  max_points = std::max<std::size_t>(1, max_points);
  return std::max<std::size_t>(1, (with_depth + max_points - 1) / max_points);
}

// Which keypoints of a frame a RANSAC reads: those with depth, and of them those `only` marks (if set).
struct KeypointFilter {
  const std::vector<bool>* only = nullptr;
  bool operator()(const Frame& f, std::size_t i) const {
    return f.depth_sigma[i] > 0.0F && (only == nullptr || (*only)[i]);
  }
};

// estimate_frame_motion on every stride-th current keypoint the filter takes.
std::optional<Eigen::Isometry3d> estimate_on_subset(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                    const TrackerOptions& options,
                                                    const std::optional<Eigen::Isometry3d>& prior,
                                                    std::vector<bool>* moving, std::optional<RivalMotion>* rival,
                                                    std::size_t stride, KeypointFilter last_filter = {},
                                                    KeypointFilter cur_filter = {}) {
  if (rival != nullptr) rival->reset();
  std::vector<Descriptor> last_desc, cur_desc;
  std::vector<Eigen::Vector3d> last_pts, cur_pts;
  std::vector<int> cur_cell;  // coverage cell of each current point
  std::vector<std::size_t> cur_keypoint;  // keypoint index of each current point
  for (std::size_t i = 0; i < last.size(); ++i) {
    if (!last_filter(last, i)) continue;
    last_desc.push_back(last.descriptors[i]);
    last_pts.push_back(camera.unproject(Eigen::Vector2d(last.keypoints[i].x, last.keypoints[i].y), last.depth[i]));
  }
  // Consensus is judged by the image area its points cover first, their number second: an object that
  // moves with the camera may hold more matches than the static scene, but the scene spreads wider.
  const double cell_size = options.ransac_coverage_cell;
  const bool by_coverage = cell_size > 0.0;
  const int cells_x = by_coverage ? std::max(1, static_cast<int>(std::ceil(std::max(camera.width, 1) / cell_size))) : 1;
  auto cell_of = [&](const Keypoint& kp) {
    if (!by_coverage) return 0;  // ranked by size only
    const int cx = std::max(0, static_cast<int>(kp.x / cell_size));
    const int cy = std::max(0, static_cast<int>(kp.y / cell_size));
    return cy * cells_x + std::min(cx, cells_x - 1);
  };
  std::size_t seen = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!cur_filter(frame, i)) continue;
    if (seen++ % stride != 0) continue;
    cur_desc.push_back(frame.descriptors[i]);
    cur_pts.push_back(camera.unproject(Eigen::Vector2d(frame.keypoints[i].x, frame.keypoints[i].y), frame.depth[i]));
    cur_cell.push_back(cell_of(frame.keypoints[i]));
    cur_keypoint.push_back(i);
  }
  const auto matches = detail::match_brute_force(cur_desc, last_desc, options.ransac_max_hamming, options.ransac_ratio);
  const int n = static_cast<int>(matches.size());
  if (n < options.ransac_min_inliers) return std::nullopt;
  // The road does not move: a consensus is ranked by the ground cells it covers before all others, so
  // a truck alongside at the ego speed, however much of the image it fills, cannot win over the scene.
  const std::vector<bool> ground =
      by_coverage && options.ransac_ground_first ? ground_points(cur_pts, options) : std::vector<bool>{};
  auto fit = [&](std::span<const int> idx) {
    Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(idx.size())), b(3, static_cast<Eigen::Index>(idx.size()));
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const auto& [q, t] = matches[static_cast<std::size_t>(idx[k])];
      a.col(static_cast<Eigen::Index>(k)) = last_pts[static_cast<std::size_t>(t)];
      b.col(static_cast<Eigen::Index>(k)) = cur_pts[static_cast<std::size_t>(q)];
    }
    Eigen::Isometry3d T;
    T.matrix() = Eigen::umeyama(a, b, false);
    return T;
  };
  std::vector<int> all(static_cast<std::size_t>(n));
  for (int m = 0; m < n; ++m) all[static_cast<std::size_t>(m)] = m;
  std::span<const int> pool = all;  // the matches a consensus may take
  auto inliers_of = [&](const Eigen::Isometry3d& T, std::vector<int>& out) {
    out.clear();
    for (const int m : pool) {
      const auto& [q, t] = matches[static_cast<std::size_t>(m)];
      const Eigen::Vector3d& pc = cur_pts[static_cast<std::size_t>(q)];
      if ((T * last_pts[static_cast<std::size_t>(t)] - pc).norm() < depth_tolerance(pc.z(), options)) out.push_back(m);
    }
  };
  // Refit on the consensus and recount (twice: the first fit may still lean on a few outliers).
  auto refine = [&](Eigen::Isometry3d& T, std::vector<int>& consensus) {
    for (int round = 0; round < 2 && static_cast<int>(consensus.size()) >= 3; ++round) {
      T = fit(consensus);
      inliers_of(T, consensus);
    }
  };
  using Score = std::tuple<long, long, std::size_t>;  // ground cells, cells, points
  std::vector<int> cell_marks, ground_marks;
  auto score_of = [&](const std::vector<int>& consensus) {
    if (!by_coverage) return Score(0L, 0L, consensus.size());
    cell_marks.clear();
    ground_marks.clear();
    for (const int m : consensus) {
      const auto q = static_cast<std::size_t>(matches[static_cast<std::size_t>(m)].first);
      cell_marks.push_back(cur_cell[q]);
      if (!ground.empty() && ground[q]) ground_marks.push_back(cur_cell[q]);
    }
    const auto distinct = [](std::vector<int>& v) {
      std::sort(v.begin(), v.end());
      return static_cast<long>(std::unique(v.begin(), v.end()) - v.begin());
    };
    return Score(distinct(ground_marks), distinct(cell_marks), consensus.size());
  };
  // Seeds: matched points that agree with T (static) or lie beyond motion_gate_factor tolerances
  // (moving); other keypoints with depth take the label of the nearest seed within
  // moving_label_radius px at a continuous depth (one rigid surface).
  auto label_moving = [&](const Eigen::Isometry3d& T, std::vector<bool>* labels) {
    labels->assign(frame.size(), false);
    if (options.motion_gate_factor <= 0.0 || options.moving_label_radius <= 0.0) return;
    std::vector<signed char> seed(frame.size(), -1);  // -1 none, 0 static, 1 moving
    for (int m = 0; m < n; ++m) {
      const auto& [q, t] = matches[static_cast<std::size_t>(m)];
      const Eigen::Vector3d& pc = cur_pts[static_cast<std::size_t>(q)];
      const double tolerance = depth_tolerance(pc.z(), options);
      const double error = (T * last_pts[static_cast<std::size_t>(t)] - pc).norm();
      const std::size_t k = cur_keypoint[static_cast<std::size_t>(q)];
      if (error < tolerance) seed[k] = 0;
      else if (error > options.motion_gate_factor * tolerance) seed[k] = 1;
    }
    std::vector<int> near;
    const auto radius = static_cast<float>(options.moving_label_radius);
    const auto continuous = [&](std::size_t a, std::size_t b) {
      return std::abs(frame.depth[a] - frame.depth[b]) <= depth_tolerance(frame.depth[a], options);
    };
    for (std::size_t i = 0; i < frame.size(); ++i) {
      if (seed[i] == 1) {
        (*labels)[i] = true;
        continue;
      }
      if (seed[i] == 0 || frame.depth_sigma[i] <= 0.0F) continue;
      const Keypoint& kp = frame.keypoints[i];
      frame.grid.query(kp.x, kp.y, radius, 0, -1, near);
      float best = std::numeric_limits<float>::max();
      signed char label = 0;
      for (const int j : near) {
        const auto sj = static_cast<std::size_t>(j);
        if (seed[sj] < 0 || !continuous(i, sj)) continue;
        const float dx = frame.keypoints[sj].x - kp.x, dy = frame.keypoints[sj].y - kp.y;
        const float d2 = dx * dx + dy * dy;
        if (d2 < best) {
          best = d2;
          label = seed[sj];
        }
      }
      (*labels)[i] = label == 1;
    }
  };
  const bool use_prior = prior.has_value();
  auto near_prior = [&](const Eigen::Isometry3d& T) {
    const double translation = (T.translation() - prior->translation()).norm();
    const double rotation = Eigen::AngleAxisd(T.linear() * prior->linear().transpose()).angle();
    return translation <= options.ransac_prior_translation +
                              options.ransac_prior_relative * prior->translation().norm() &&
           rotation <= options.ransac_prior_rotation_deg * std::numbers::pi / 180.0;
  };
  // 3-point samples of the matches in `pool`, ransac_iterations of them (fixed seeds: deterministic);
  // consider(T, consensus, score) sees each sampled motion, best(...) keeps the best-scoring one.
  std::vector<int> current;
  auto sample_motions = [&](unsigned seed, const auto& consider) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    for (int it = 0; it < options.ransac_iterations; ++it) {
      const std::array<int, 3> sample = {pool[pick(rng)], pool[pick(rng)], pool[pick(rng)]};
      if (sample[0] == sample[1] || sample[1] == sample[2] || sample[0] == sample[2]) continue;
      const Eigen::Isometry3d T = fit(sample);
      inliers_of(T, current);
      consider(T, score_of(current));
    }
  };
  struct Best {
    std::vector<int> consensus;
    Score score{-1, -1, 0};
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  };
  auto keep_if_better = [&](Best& b, const Eigen::Isometry3d& T, const Score& score) {
    if (!(score > b.score)) return;
    b.consensus = current;
    b.score = score;
    b.T = T;
  };
  Best best, near;
  if (use_prior) {
    // The prior itself, refined, is the first near hypothesis: sampling alone may miss the static
    // scene when a moving object holds most of the matches.
    near.T = *prior;
    inliers_of(near.T, near.consensus);
    refine(near.T, near.consensus);
    if (!near_prior(near.T)) near.consensus.clear();
    near.score = score_of(near.consensus);
  }
  sample_motions(7, [&](const Eigen::Isometry3d& T, const Score& score) {
    if (use_prior && near_prior(T)) keep_if_better(near, T, score);
    keep_if_better(best, T, score);
  });
  if (use_prior) {
    // The constant-velocity prior is trusted: refine it with the near consensus, or keep it as is;
    // never jump to a far motion (a real jump in the input is caught later, by the verification).
    if (near.consensus.empty()) return std::nullopt;
    refine(near.T, near.consensus);
    if (!near_prior(near.T) || static_cast<int>(near.consensus.size()) < options.ransac_min_inliers) return std::nullopt;
    if (moving != nullptr) label_moving(near.T, moving);
    if (!best.consensus.empty() && best.consensus.size() > near.consensus.size() && !near_prior(best.T)) {
      logger()->debug("frame {}: depth RANSAC keeps the motion near constant velocity ({} inliers) over another "
                      "({} inliers, {:.2f} m from it)", frame.index, near.consensus.size(), best.consensus.size(),
                      (best.T.translation() - prior->translation()).norm());
    }
    return near.T;
  }
  refine(best.T, best.consensus);
  if (static_cast<int>(best.consensus.size()) < options.ransac_min_inliers) return std::nullopt;
  if (moving != nullptr) label_moving(best.T, moving);
  if (rival != nullptr) {
    // The same sampling on the matches the winner leaves out (its own seed, so the winner is unchanged).
    std::vector<int> rest;
    std::set_difference(all.begin(), all.end(), best.consensus.begin(), best.consensus.end(), std::back_inserter(rest));
    if (static_cast<int>(rest.size()) >= kMinRivalInliers) {
      pool = rest;
      Best second;
      sample_motions(13, [&](const Eigen::Isometry3d& T, const Score& score) { keep_if_better(second, T, score); });
      refine(second.T, second.consensus);
      if (static_cast<int>(second.consensus.size()) >= kMinRivalInliers) {
        RivalMotion r;
        r.T_cur_last = second.T;
        r.inliers = second.consensus.size();
        if (moving != nullptr) label_moving(second.T, &r.moving);
        *rival = std::move(r);
      }
    }
  }
  return best.T;
}

}  // namespace

// Why: breaks the feedback of the constant-velocity prediction on periodic or weak texture (fences,
// grass), where guided matching around a slightly wrong prediction finds matches that confirm it; the
// prior keeps a rigid object that moves with the camera (a van ahead at the same speed) from taking
// over when its corners outnumber the static scene's.
std::optional<Eigen::Isometry3d> estimate_frame_motion(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                       const TrackerOptions& options,
                                                       const std::optional<Eigen::Isometry3d>& prior,
                                                       std::vector<bool>* moving,
                                                       std::optional<RivalMotion>* rival) {
  // A strided subset of the current keypoints bounds the cost (options.hpp).
  const auto with_depth = static_cast<std::size_t>(
      std::count_if(frame.depth_sigma.begin(), frame.depth_sigma.end(), [](float s) { return s > 0.0F; }));
  const std::size_t first =
      subset_stride(with_depth, prior ? options.ransac_max_points_near_prior : options.ransac_max_points);
  auto T = estimate_on_subset(camera, last, frame, options, prior, moving, rival, first);
  // Near a prior only the prior's neighbourhood can win, so when the subset holds too few of the
  // scene's matches (vehicles hiding most of it) the other keypoints are evidence; a retry whose
  // subset is no larger would only repeat the first.
  const std::size_t retry = subset_stride(with_depth, options.ransac_max_points_near_prior_retry);
  if (!T && prior && options.ransac_max_points_near_prior_retry > 0 && retry < first) {
    logger()->debug("frame {}: too few matches near the prior on the subset of stride {}, again with stride {}",
                    frame.index, first, retry);
    T = estimate_on_subset(camera, last, frame, options, prior, moving, rival, retry);
  }
  return T;
}

std::optional<Eigen::Isometry3d> estimate_road_motion(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                      const TrackerOptions& options) {
  const std::vector<bool> last_road = ground_keypoints(camera, last, options);
  const std::vector<bool> road = ground_keypoints(camera, frame, options);
  if (last_road.empty() || road.empty()) return std::nullopt;
  const auto on_road = static_cast<std::size_t>(std::count(road.begin(), road.end(), true));
  TrackerOptions guess = options;
  guess.ransac_min_inliers = options.ransac_guess_min_inliers;
  return estimate_on_subset(camera, last, frame, guess, std::nullopt, nullptr, nullptr,
                            subset_stride(on_road, options.ransac_max_points), KeypointFilter{&last_road},
                            KeypointFilter{&road});
}

RayFits fits_by_rays(const PinholeCamera& camera, const Frame& last, const Frame& frame, const Eigen::Isometry3d& T_a,
                     const Eigen::Isometry3d& T_b, int max_hamming, double scale_factor) {
  std::vector<std::size_t> rows;  // last's keypoints without depth
  std::vector<Descriptor> query;
  for (std::size_t i = 0; i < last.size(); ++i) {
    if (last.depth[i] > 0.0F) continue;
    rows.push_back(i);
    query.push_back(last.descriptors[i]);
  }
  const auto fits = [&](const Eigen::Isometry3d& T, const Eigen::Vector3d& ray, const Keypoint& k) {
    // clipped to the image widened by the radius: a keypoint in the image within the radius of the
    // whole segment is within it of the clipped one
    const double radius = 2.0 * std::pow(scale_factor, k.level);
    const auto segment = epipolar_segment(T, ray, 2.0 + 1.5 * T.translation().norm(), camera, radius);
    return segment && distance_to_segment(Eigen::Vector2d(k.x, k.y), segment->first, segment->second) <= radius;
  };
  RayFits result;
  for (const auto& [q, t] : detail::match_brute_force(query, frame.descriptors, max_hamming, 0.8)) {
    const Keypoint& k_last = last.keypoints[rows[static_cast<std::size_t>(q)]];
    const Eigen::Vector3d ray = camera.unproject(Eigen::Vector2d(k_last.x, k_last.y), 1.0);  // z = 1
    const Keypoint& k = frame.keypoints[static_cast<std::size_t>(t)];
    const bool on_a = fits(T_a, ray, k);
    const bool on_b = fits(T_b, ray, k);
    ++result.matches;
    result.a_only += on_a && !on_b ? 1 : 0;
    result.b_only += on_b && !on_a ? 1 : 0;
  }
  return result;
}

}  // namespace rgbl
