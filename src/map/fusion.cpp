#include "rgbl/map/fusion.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/features/matcher.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <vector>

namespace rgbl {

void FusionOptions::validate() const {
  require(radius_px > 0.0, "fusion.radius_px", "> 0 px");
  require(max_hamming >= 0 && max_hamming <= 256, "fusion.max_hamming", "a Hamming distance in [0, 256]");
}

int fuse_landmarks(Map& map, const PinholeCamera& camera, KeyframeId target_id, std::span<const LandmarkId> landmarks,
                   const FusionOptions& options) {
  const Keyframe* target = map.keyframe(target_id);
  if (target == nullptr) return 0;
  const FeatureGrid grid(target->keypoints, camera.width, camera.height);
  const Eigen::Vector3d center = target->center();
  const double scale = map.options().scale_factor;
  const int levels = map.options().levels;
  constexpr double kChi2Pixel = 5.991, kChi2PixelDepth = 7.815;  // 95 % for 2 and 3 dof
  std::vector<int> cell;
  int fused = 0;
  for (const LandmarkId id : landmarks) {
    const Landmark* l = map.landmark(id);
    target = map.keyframe(target_id);  // merging below may have changed the keyframe's slots
    if (l == nullptr || target == nullptr || l->observations.count(target_id) != 0) continue;
    const Eigen::Vector3d p = target->T_cam_world * l->position;
    if (p.z() <= 0.0) continue;
    const Eigen::Vector2d px = camera.project_unchecked(p);
    if (!camera.in_image(px)) continue;
    const Eigen::Vector3d ray = l->position - center;
    const double distance = ray.norm();
    if (distance < 0.8 * l->min_distance || distance > 1.2 * l->max_distance) continue;
    if (ray.dot(l->normal) < 0.5 * distance) continue;
    const int level = l->predict_level(distance, levels, scale);
    const double radius = options.radius_px * std::pow(scale, level);
    grid.query(static_cast<float>(px.x()), static_cast<float>(px.y()), static_cast<float>(radius),
               std::max(0, level - 1), level, cell);
    int best = INT_MAX, best_index = -1;
    for (const int k : cell) {
      const auto ks = static_cast<std::size_t>(k);
      const Keypoint& kp = target->keypoints[ks];
      const double sigma = std::pow(scale, kp.level);
      double chi2 = (Eigen::Vector2d(kp.x, kp.y) - px).squaredNorm() / (sigma * sigma);
      double threshold = kChi2Pixel;
      if (target->depth_sigma[ks] > 0.0F) {
        const double dz = (p.z() - target->depth[ks]) / target->depth_sigma[ks];
        chi2 += dz * dz;
        threshold = kChi2PixelDepth;
      }
      if (chi2 > threshold) continue;
      const int d = hamming_distance(l->descriptor, target->descriptors[ks]);
      if (d < best) {
        best = d;
        best_index = k;
      }
    }
    if (best_index < 0 || best > options.max_hamming) continue;
    const LandmarkId existing = target->landmarks[static_cast<std::size_t>(best_index)];
    if (existing.valid()) {
      const Landmark* e = map.landmark(existing);
      if (e == nullptr) continue;
      if (e->observations.size() > l->observations.size()) map.replace_landmark(id, existing);
      else map.replace_landmark(existing, id);
    } else {
      map.add_observation(id, target_id, best_index);
    }
    ++fused;
  }
  return fused;
}

}  // namespace rgbl
