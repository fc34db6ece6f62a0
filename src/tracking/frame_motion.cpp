#include "rgbl/tracking/frame_motion.hpp"

#include "matching.hpp"
#include "rgbl/core/log.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

namespace rgbl {

// Why: breaks the feedback of the constant-velocity prediction on periodic or weak texture (fences,
// grass), where guided matching around a slightly wrong prediction finds matches that confirm it; the
// prior keeps a rigid object that moves with the camera (a van ahead at the same speed) from taking
// over when its corners outnumber the static scene's.
std::optional<Eigen::Isometry3d> estimate_frame_motion(const PinholeCamera& camera, const Frame& last, const Frame& frame,
                                                       const TrackerOptions& options,
                                                       const std::optional<Eigen::Isometry3d>& prior) {
  std::vector<Descriptor> last_desc, cur_desc;
  std::vector<Eigen::Vector3d> last_pts, cur_pts;
  std::vector<int> cur_cell;  // coverage cell of each current point
  for (std::size_t i = 0; i < last.size(); ++i) {
    if (last.depth_sigma[i] <= 0.0F) continue;
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
  // A strided subset of the current keypoints is enough for a 6-DoF consensus and bounds the cost.
  std::size_t with_depth = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) with_depth += frame.depth_sigma[i] > 0.0F ? 1 : 0;
  const std::size_t stride = std::max<std::size_t>(1, (with_depth + options.ransac_max_points - 1) /
                                                          std::max<std::size_t>(1, options.ransac_max_points));
  std::size_t seen = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.depth_sigma[i] <= 0.0F) continue;
    if (seen++ % stride != 0) continue;
    cur_desc.push_back(frame.descriptors[i]);
    cur_pts.push_back(camera.unproject(Eigen::Vector2d(frame.keypoints[i].x, frame.keypoints[i].y), frame.depth[i]));
    cur_cell.push_back(cell_of(frame.keypoints[i]));
  }
  const auto matches = detail::match_brute_force(cur_desc, last_desc, options.ransac_max_hamming, options.ransac_ratio);
  const int n = static_cast<int>(matches.size());
  if (n < options.ransac_min_inliers) return std::nullopt;
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
  auto inliers_of = [&](const Eigen::Isometry3d& T, std::vector<int>& out) {
    out.clear();
    for (int m = 0; m < n; ++m) {
      const auto& [q, t] = matches[static_cast<std::size_t>(m)];
      const Eigen::Vector3d& pc = cur_pts[static_cast<std::size_t>(q)];
      const double tolerance = std::max(options.ransac_min_tolerance, options.ransac_relative_tolerance * pc.z());
      if ((T * last_pts[static_cast<std::size_t>(t)] - pc).norm() < tolerance) out.push_back(m);
    }
  };
  // Refit on the consensus and recount (twice: the first fit may still lean on a few outliers).
  auto refine = [&](Eigen::Isometry3d& T, std::vector<int>& consensus) {
    for (int round = 0; round < 2 && static_cast<int>(consensus.size()) >= 3; ++round) {
      T = fit(consensus);
      inliers_of(T, consensus);
    }
  };
  std::vector<int> cell_marks;
  auto score_of = [&](const std::vector<int>& consensus) {
    if (!by_coverage) return std::pair<long, std::size_t>(0L, consensus.size());
    cell_marks.clear();
    for (const int m : consensus) cell_marks.push_back(cur_cell[static_cast<std::size_t>(matches[static_cast<std::size_t>(m)].first)]);
    std::sort(cell_marks.begin(), cell_marks.end());
    const auto cells = std::unique(cell_marks.begin(), cell_marks.end()) - cell_marks.begin();
    return std::pair<long, std::size_t>(static_cast<long>(cells), consensus.size());
  };
  const bool use_prior = prior.has_value();
  auto near_prior = [&](const Eigen::Isometry3d& T) {
    const double translation = (T.translation() - prior->translation()).norm();
    const double rotation = Eigen::AngleAxisd(T.linear() * prior->linear().transpose()).angle();
    return translation <= options.ransac_prior_translation +
                              options.ransac_prior_relative * prior->translation().norm() &&
           rotation <= options.ransac_prior_rotation_deg * std::numbers::pi / 180.0;
  };
  std::mt19937 rng(7);  // fixed seed: deterministic
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<int> best, best_near, current;
  std::pair<long, std::size_t> best_score{-1, 0}, near_score{-1, 0};
  Eigen::Isometry3d T_best = Eigen::Isometry3d::Identity(), T_near = Eigen::Isometry3d::Identity();
  if (use_prior) {
    // The prior itself, refined, is the first near hypothesis: sampling alone may miss the static
    // scene when a moving object holds most of the matches.
    T_near = *prior;
    inliers_of(T_near, best_near);
    refine(T_near, best_near);
    if (!near_prior(T_near)) best_near.clear();
    near_score = score_of(best_near);
  }
  for (int it = 0; it < options.ransac_iterations; ++it) {
    const std::array<int, 3> sample = {pick(rng), pick(rng), pick(rng)};
    if (sample[0] == sample[1] || sample[1] == sample[2] || sample[0] == sample[2]) continue;
    const Eigen::Isometry3d T = fit(sample);
    inliers_of(T, current);
    const auto score = score_of(current);
    if (use_prior && score > near_score && near_prior(T)) {
      best_near = current;
      near_score = score;
      T_near = T;
    }
    if (score > best_score) {
      best.swap(current);
      best_score = score;
      T_best = T;
    }
  }
  if (use_prior) {
    // The constant-velocity prior is trusted: refine it with the near consensus, or keep it as is;
    // never jump to a far motion (a real jump in the input is caught later, by the verification).
    if (best_near.empty()) return std::nullopt;
    refine(T_near, best_near);
    if (!near_prior(T_near) || static_cast<int>(best_near.size()) < options.ransac_min_inliers) return std::nullopt;
    if (!best.empty() && best.size() > best_near.size() && !near_prior(T_best)) {
      logger()->debug("frame {}: depth RANSAC keeps the motion near constant velocity ({} inliers) over another "
                      "({} inliers, {:.2f} m from it)", frame.index, best_near.size(), best.size(),
                      (T_best.translation() - prior->translation()).norm());
    }
    return T_near;
  }
  refine(T_best, best);
  if (static_cast<int>(best.size()) < options.ransac_min_inliers) return std::nullopt;
  return T_best;
}

}  // namespace rgbl
