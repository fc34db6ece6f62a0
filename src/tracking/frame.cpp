#include "rgbl/tracking/frame.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/tracking/options.hpp"

#include <algorithm>
#include <cmath>

namespace rgbl {

KeypointGrid::KeypointGrid(std::span<const Keypoint> keypoints, int width, int height, int cell_size)
    : keypoints_(keypoints), cell_size_(std::max(cell_size, 1)) {
  columns_ = std::max(1, (width + cell_size_ - 1) / cell_size_);
  rows_ = std::max(1, (height + cell_size_ - 1) / cell_size_);
  const std::size_t cells = static_cast<std::size_t>(columns_) * static_cast<std::size_t>(rows_);
  std::vector<int> cell_of(keypoints.size());
  cell_start_.assign(cells + 1, 0);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const int cx = std::clamp(static_cast<int>(keypoints[i].x + 0.5F) / cell_size_, 0, columns_ - 1);
    const int cy = std::clamp(static_cast<int>(keypoints[i].y + 0.5F) / cell_size_, 0, rows_ - 1);
    cell_of[i] = cy * columns_ + cx;
    ++cell_start_[static_cast<std::size_t>(cell_of[i]) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  indices_.resize(keypoints.size());
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    indices_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = static_cast<int>(i);
  }
}

void KeypointGrid::query(float x, float y, float radius, int min_level, int max_level, std::vector<int>& out) const {
  out.clear();
  if (columns_ == 0) return;
  const int x0 = std::max(0, static_cast<int>(std::floor((x - radius + 0.5F) / cell_size_)));
  const int x1 = std::min(columns_ - 1, static_cast<int>(std::floor((x + radius + 0.5F) / cell_size_)));
  const int y0 = std::max(0, static_cast<int>(std::floor((y - radius + 0.5F) / cell_size_)));
  const int y1 = std::min(rows_ - 1, static_cast<int>(std::floor((y + radius + 0.5F) / cell_size_)));
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      const std::size_t c = static_cast<std::size_t>(cy * columns_ + cx);
      for (int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const Keypoint& kp = keypoints_[static_cast<std::size_t>(indices_[static_cast<std::size_t>(k)])];
        if (kp.level < min_level || (max_level >= 0 && kp.level > max_level)) continue;
        if (std::abs(kp.x - x) > radius || std::abs(kp.y - y) > radius) continue;
        out.push_back(indices_[static_cast<std::size_t>(k)]);
      }
    }
  }
}

void TrackerOptions::validate() const {
  require(min_initial_depth_points >= 10, "tracker.min_initial_depth_points", ">= 10");
  require(motion_radius > 0.0, "tracker.motion_radius", "> 0");
  require(local_map_radius > 0.0, "tracker.local_map_radius", "> 0");
  require(max_hamming > 0 && max_hamming <= 256, "tracker.max_hamming", "in (0, 256]");
  require(local_map_ratio > 0.0 && local_map_ratio <= 1.0, "tracker.local_map_ratio", "in (0, 1]");
  require(reference_ratio > 0.0 && reference_ratio <= 1.0, "tracker.reference_ratio", "in (0, 1]");
  require(max_local_keyframes >= 1, "tracker.max_local_keyframes", ">= 1");
  require(min_pose_inliers >= 3, "tracker.min_pose_inliers", ">= 3");
  require(relocalisation_min_matches >= 6, "tracker.relocalisation_min_matches", ">= 6 (PnP RANSAC)");
  require(max_frames_between_keyframes >= 1, "tracker.max_frames_between_keyframes", ">= 1");
  require(close_depth > 0.0, "tracker.close_depth", "> 0");
  pose.validate();
}

void LocalMappingOptions::validate() const {
  require(min_new_depth_points >= 0, "local_mapping.min_new_depth_points", ">= 0");
  require(max_new_depth_points >= min_new_depth_points, "local_mapping.max_new_depth_points",
          ">= min_new_depth_points");
  require(max_local_ba_keyframes >= 1, "local_mapping.max_local_ba_keyframes", ">= 1");
  require(min_found_ratio >= 0.0 && min_found_ratio <= 1.0, "local_mapping.min_found_ratio", "in [0, 1]");
  require(redundant_ratio > 0.0 && redundant_ratio <= 1.0, "local_mapping.redundant_ratio", "in (0, 1]");
  ba.validate();
}

}  // namespace rgbl
