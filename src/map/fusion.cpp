#include "rgbl/map/fusion.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/features/matcher.hpp"
#include "rgbl/map/landmark_view.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <vector>

namespace rgbl {

void FusionOptions::validate() const {
  require(radius_px > 0.0, "fusion.radius_px", "> 0 px");
  require(max_hamming >= 0 && max_hamming <= 256, "fusion.max_hamming", "a Hamming distance in [0, 256]");
  require(min_view_cos >= -1.0 && min_view_cos <= 1.0, "fusion.min_view_cos", "a cosine in [-1, 1]");
}

int fuse_landmarks(Map& map, const PinholeCamera& camera, KeyframeId target_id, std::span<const LandmarkId> landmarks,
                   const FusionOptions& options) {
  const Keyframe* target = map.keyframe(target_id);
  if (target == nullptr) return 0;
  const FeatureGrid grid(target->keypoints, camera.width, camera.height);
  const Eigen::Vector3d center = target->center();
  const double scale = map.options().scale_factor;
  constexpr double kChi2Pixel = 5.991, kChi2PixelDepth = 7.815;  // 95 % for 2 and 3 dof
  std::vector<int> cell;
  int fused = 0;
  for (const LandmarkId id : landmarks) {
    const Landmark* l = map.landmark(id);
    target = map.keyframe(target_id);  // merging below may have changed the keyframe's slots
    if (l == nullptr || target == nullptr || l->observations.count(target_id) != 0) continue;
    const auto view = view_landmark(*l, target->T_cam_world, center, camera, map.options(), options.min_view_cos);
    if (!view) continue;
    const double radius = options.radius_px * std::pow(scale, view->level);
    grid.query(static_cast<float>(view->pixel.x()), static_cast<float>(view->pixel.y()), static_cast<float>(radius),
               std::max(0, view->level - 1), view->level, cell);
    int best = INT_MAX, best_index = -1;
    for (const int k : cell) {
      const auto ks = static_cast<std::size_t>(k);
      const Keypoint& kp = target->keypoints[ks];
      const double sigma = std::pow(scale, kp.level);
      double chi2 = (Eigen::Vector2d(kp.x, kp.y) - view->pixel).squaredNorm() / (sigma * sigma);
      double threshold = kChi2Pixel;
      if (target->depth_sigma[ks] > 0.0F) {
        const double dz = (view->p_cam.z() - target->depth[ks]) / target->depth_sigma[ks];
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
