#include "rgbl/map/triangulation.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/features/matcher.hpp"
#include "rgbl/geometry/epipolar.hpp"
#include "rgbl/geometry/se3.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

namespace rgbl {

void TriangulationOptions::validate() const {
  require(covisible_keyframes >= 1, "triangulation.covisible_keyframes", ">= 1");
  require(max_hamming >= 0 && max_hamming <= 256, "triangulation.max_hamming", "a Hamming distance in [0, 256]");
  require(max_ratio > 0.0 && max_ratio <= 1.0, "triangulation.max_ratio", "in (0, 1]");
  require(min_parallax_deg > 0.0 && min_parallax_deg < 90.0, "triangulation.min_parallax_deg", "in (0, 90) degrees");
  require(min_depth > 0.0, "triangulation.min_depth", "> 0 m");
  require(max_depth_sigma_relative > 0.0, "triangulation.max_depth_sigma_relative", "> 0");
  require(min_baseline_ratio >= 0.0, "triangulation.min_baseline_ratio", ">= 0");
  require(moving_radius_px >= 0.0, "triangulation.moving_radius_px", ">= 0 px");
}

namespace {

constexpr double kChi2Line = 3.841;   // 95 %, 1 dof: distance to the epipolar line
constexpr double kChi2Pixel = 5.991;  // 95 %, 2 dof: reprojection

// A keypoint that may become a triangulated landmark: no landmark, no depth, no refused depth (unless
// asked), and not next to something the tracker found moving (the keyframe keeps a moving keypoint's
// depth with a zero sigma).
std::vector<bool> open_keypoints(const Keyframe& kf, const PinholeCamera& camera, const TriangulationOptions& options) {
  std::vector<std::size_t> moving;
  for (std::size_t i = 0; i < kf.depth.size(); ++i) {
    if (kf.depth[i] > 0.0F && kf.depth_sigma[i] <= 0.0F) moving.push_back(i);
  }
  const auto radius = static_cast<float>(options.moving_radius_px);
  std::optional<FeatureGrid> grid;  // built when a keypoint is near something moving
  std::vector<int> cell;
  std::vector<bool> open(kf.keypoints.size(), false);
  for (std::size_t i = 0; i < kf.keypoints.size(); ++i) {
    if (kf.landmarks[i].valid() || kf.depth[i] > 0.0F) continue;
    if (!options.include_refused_depth && i < kf.depth_refused.size() && kf.depth_refused[i]) continue;
    const Keypoint& kp = kf.keypoints[i];
    const bool near_moving = std::any_of(moving.begin(), moving.end(), [&](std::size_t m) {
      return std::abs(kf.keypoints[m].x - kp.x) <= radius && std::abs(kf.keypoints[m].y - kp.y) <= radius;
    });
    bool on_moving = false;
    if (near_moving) {
      if (!grid) grid.emplace(kf.keypoints, camera.width, camera.height);
      grid->query(kp.x, kp.y, radius, 0, -1, cell);
      float nearest = INFINITY;
      for (const int k : cell) {
        const auto ks = static_cast<std::size_t>(k);
        if (kf.depth[ks] <= 0.0F) continue;
        const float dx = kf.keypoints[ks].x - kp.x, dy = kf.keypoints[ks].y - kp.y;
        if (const float d = dx * dx + dy * dy; d < nearest) {
          nearest = d;
          on_moving = kf.depth_sigma[ks] <= 0.0F;
        }
      }
    }
    open[i] = !on_moving;
  }
  return open;
}

// The open keypoints of a keyframe bucketed in square cells.
class OpenCells {
 public:
  OpenCells(const Keyframe& kf, const std::vector<bool>& open, int width, int height, double cell)
      : cell_(cell), cols_(std::max(1, static_cast<int>(std::ceil(width / cell)))),
        rows_(std::max(1, static_cast<int>(std::ceil(height / cell)))) {
    std::vector<int> count(static_cast<std::size_t>(cols_ * rows_) + 1, 0);
    for (std::size_t j = 0; j < open.size(); ++j) {
      if (open[j]) ++count[cell_of(kf.keypoints[j].x, kf.keypoints[j].y) + 1];
    }
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    offsets_ = count;
    indices_.resize(static_cast<std::size_t>(count.back()));
    for (std::size_t j = 0; j < open.size(); ++j) {
      if (open[j]) indices_[static_cast<std::size_t>(count[cell_of(kf.keypoints[j].x, kf.keypoints[j].y)]++)] = j;
    }
  }

  // Calls visit(j) once for each open keypoint in a cell within `margin` px of the segment a-b: cell
  // columns (or rows, for a steep segment) across its extent, in each the cells its band crosses.
  template <class Visit>
  void along_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double margin, Visit&& visit) const {
    const bool by_x = std::abs(b.x() - a.x()) >= std::abs(b.y() - a.y());
    const int major = by_x ? 0 : 1, minor = 1 - major;
    const int major_cells = by_x ? cols_ : rows_, minor_cells = by_x ? rows_ : cols_;
    const Eigen::Vector2d lo = a(major) <= b(major) ? a : b, hi = a(major) <= b(major) ? b : a;
    const double run = hi(major) - lo(major);
    const double slope = run > 0.0 ? (hi(minor) - lo(minor)) / run : 0.0;
    // the band's half-width along the minor axis (at most sqrt(2) margin: the slope is at most 1)
    const double half = margin * std::sqrt(1.0 + slope * slope);
    const int c0 = std::max(0, static_cast<int>(std::floor((lo(major) - margin) / cell_)));
    const int c1 = std::min(major_cells - 1, static_cast<int>(std::floor((hi(major) + margin) / cell_)));
    for (int c = c0; c <= c1; ++c) {
      // the segment's minor coordinate over this column, its ends held beyond the segment
      const double m0 = std::clamp(c * cell_, lo(major), hi(major)), m1 = std::clamp((c + 1) * cell_, lo(major), hi(major));
      const double v0 = lo(minor) + slope * (m0 - lo(major)), v1 = lo(minor) + slope * (m1 - lo(major));
      const int r0 = std::max(0, static_cast<int>(std::floor((std::min(v0, v1) - half) / cell_)));
      const int r1 = std::min(minor_cells - 1, static_cast<int>(std::floor((std::max(v0, v1) + half) / cell_)));
      for (int r = r0; r <= r1; ++r) {
        const auto cell = static_cast<std::size_t>(by_x ? r * cols_ + c : c * cols_ + r);
        for (int k = offsets_[cell]; k < offsets_[cell + 1]; ++k) visit(indices_[static_cast<std::size_t>(k)]);
      }
    }
  }

 private:
  std::size_t cell_of(float x, float y) const {
    const int cx = std::clamp(static_cast<int>(x / cell_), 0, cols_ - 1);
    const int cy = std::clamp(static_cast<int>(y / cell_), 0, rows_ - 1);
    return static_cast<std::size_t>(cy * cols_ + cx);
  }

  double cell_;
  int cols_, rows_;
  std::vector<int> offsets_;
  std::vector<std::size_t> indices_;
};

struct Proposal {
  std::size_t own = 0, other = 0;
  int distance = 0;  // Hamming
};

}  // namespace

std::vector<LandmarkId> triangulate_landmarks(Map& map, const PinholeCamera& camera, KeyframeId id,
                                              const TriangulationOptions& options) {
  std::vector<LandmarkId> created;
  const Keyframe* kf = map.keyframe(id);
  if (kf == nullptr) return created;
  const double scale_factor = map.options().scale_factor;
  const int levels = map.options().levels;
  const double max_sigma = std::pow(scale_factor, levels - 1);
  const double margin = std::sqrt(kChi2Line) * max_sigma;
  const double min_cos = std::cos(options.min_parallax_deg * std::numbers::pi / 180.0);
  const double ratio_factor = 1.5 * scale_factor;  // ORB-SLAM's allowance on the pyramid's distance ratio

  std::vector<bool> own_open = open_keypoints(*kf, camera, options);
  if (std::none_of(own_open.begin(), own_open.end(), [](bool b) { return b; })) return created;
  // the rays of the new keyframe's keypoints, camera frame, z = 1
  std::vector<Eigen::Vector3d> own_rays(kf->keypoints.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < own_rays.size(); ++i) {
    if (own_open[i]) own_rays[i] = camera.unproject(Eigen::Vector2d(kf->keypoints[i].x, kf->keypoints[i].y), 1.0);
  }

  // a keypoint's pixel variance by its pyramid level (the pose optimiser's and bundle adjustment's sigma)
  std::vector<double> level_variance;
  for (int level = 0; level < std::max(levels, 1); ++level) level_variance.push_back(std::pow(scale_factor, 2 * level));
  const auto variance = [&](int level) {
    return level_variance[std::min(static_cast<std::size_t>(std::max(level, 0)), level_variance.size() - 1)];
  };
  // adding landmarks and observations below erases nothing: the keyframe pointers stay valid
  for (const KeyframeId other_id : map.best_covisible(id, static_cast<std::size_t>(options.covisible_keyframes))) {
    const Keyframe* other = map.keyframe(other_id);
    if (other == nullptr) continue;
    const Eigen::Vector3d own_centre = kf->center(), other_centre = other->center();
    const double baseline = (own_centre - other_centre).norm();
    const double depth = other->median_depth();
    if (depth <= 0.0 || baseline < options.min_baseline_ratio * depth) continue;

    const std::vector<bool> other_open = open_keypoints(*other, camera, options);
    std::vector<Eigen::Vector3d> other_rays(other->keypoints.size(), Eigen::Vector3d::Zero());
    for (std::size_t j = 0; j < other_rays.size(); ++j) {
      if (other_open[j]) other_rays[j] = camera.unproject(Eigen::Vector2d(other->keypoints[j].x, other->keypoints[j].y), 1.0);
    }
    // x_other^T E x_own = 0 on normalised rays
    const Eigen::Isometry3d T_other_own = other->T_cam_world * kf->T_cam_world.inverse();
    const Eigen::Matrix3d E = hat(T_other_own.translation()) * T_other_own.linear();

    std::vector<Proposal> proposals;
    OpenCells cells(*other, other_open, camera.width, camera.height, 16.0);
    for (std::size_t i = 0; i < own_rays.size(); ++i) {
      if (!own_open[i]) continue;
      const Eigen::Vector3d line_n = E * own_rays[i];
      const double line_norm = std::hypot(line_n.x(), line_n.y());
      if (!(line_norm > 0.0)) continue;
      const auto segment = epipolar_segment(T_other_own, own_rays[i], options.min_depth, camera, margin);
      if (!segment) continue;
      const Descriptor& descriptor = kf->descriptors[i];
      const Eigen::Vector3d line = line_n * (camera.fx / line_norm);  // distance to it as pixels at fx
      int best = INT_MAX, second = INT_MAX;
      std::size_t best_index = 0;
      cells.along_segment(segment->first, segment->second, margin, [&](std::size_t j) {
        const double distance = line.dot(other_rays[j]);
        if (distance * distance > kChi2Line * variance(other->keypoints[j].level)) return;
        const int d = hamming_distance(descriptor, other->descriptors[j]);
        if (d < best) {
          second = best;
          best = d;
          best_index = j;
        } else if (d < second) {
          second = d;
        }
      });
      if (best > options.max_hamming || !(best < options.max_ratio * second)) continue;
      proposals.push_back({i, best_index, best});
    }
    // one-to-one: a keypoint of the other keyframe goes to its closest proposal
    std::sort(proposals.begin(), proposals.end(), [](const Proposal& a, const Proposal& b) {
      return a.distance != b.distance ? a.distance < b.distance : a.own < b.own;
    });
    std::vector<bool> taken(other->keypoints.size(), false);
    const Eigen::Isometry3d T_world_own = kf->T_cam_world.inverse(), T_world_other = other->T_cam_world.inverse();
    for (const Proposal& p : proposals) {
      if (taken[p.other]) continue;
      const Eigen::Vector3d d_own = (T_world_own.linear() * own_rays[p.own]).normalized();
      const Eigen::Vector3d d_other = (T_world_other.linear() * other_rays[p.other]).normalized();
      const double cos_parallax = d_own.dot(d_other);
      if (cos_parallax > min_cos) continue;
      // the midpoint of the rays' closest approach
      const Eigen::Vector3d w = other_centre - own_centre;
      const double denom = 1.0 - cos_parallax * cos_parallax;
      const double s = (d_own.dot(w) - cos_parallax * d_other.dot(w)) / denom;
      const double u = (cos_parallax * d_own.dot(w) - d_other.dot(w)) / denom;
      if (!(s > 0.0 && u > 0.0)) continue;
      const Eigen::Vector3d X = 0.5 * (own_centre + s * d_own + other_centre + u * d_other);
      const Keypoint& kp_own = kf->keypoints[p.own];
      const Keypoint& kp_other = other->keypoints[p.other];
      const auto reprojects = [&](const Eigen::Isometry3d& T_cam_world, const Keypoint& kp) {
        const Eigen::Vector3d p_cam = T_cam_world * X;
        if (p_cam.z() <= 0.0) return false;
        return (camera.project_unchecked(p_cam) - Eigen::Vector2d(kp.x, kp.y)).squaredNorm() <= kChi2Pixel * variance(kp.level);
      };
      if (!reprojects(kf->T_cam_world, kp_own) || !reprojects(other->T_cam_world, kp_other)) continue;
      // the depth's own uncertainty: the rays' directions are known to their levels' pixel sigmas,
      // and the depth along a ray moves by sigma / parallax of itself per radian
      const double ray_sigma = std::sqrt(variance(kp_own.level) + variance(kp_other.level)) / camera.fx;
      if (ray_sigma > options.max_depth_sigma_relative * std::acos(std::clamp(cos_parallax, -1.0, 1.0))) continue;
      // the distances must fit the pyramid levels the two keypoints were found on
      const double ratio_distance = (X - own_centre).norm() / (X - other_centre).norm();
      const double ratio_octave = std::pow(scale_factor, kp_own.level - kp_other.level);
      if (ratio_distance * ratio_factor < ratio_octave || ratio_distance > ratio_octave * ratio_factor) continue;
      taken[p.other] = true;
      own_open[p.own] = false;
      const LandmarkId l = map.add_landmark(X, id);
      map.add_observation(l, id, static_cast<int>(p.own));
      map.add_observation(l, other_id, static_cast<int>(p.other));
      map.update_landmark(l);
      created.push_back(l);
    }
  }
  return created;
}

}  // namespace rgbl
