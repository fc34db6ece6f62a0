#pragma once
// One tracked frame: keypoints, descriptors, depth per keypoint and a grid for radius queries.

#include "rgbl/features/types.hpp"
#include "rgbl/map/map.hpp"

#include <Eigen/Geometry>

#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace rgbl {

// Extracts keypoints and descriptors from a greyscale image. The tracker only needs this call, so any
// extractor (rgbl's ORB, OpenCV's, a user's) can be injected.
using FeatureExtractor =
    std::function<void(const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors)>;

// Buckets keypoints into square cells for "which keypoints lie within r of (x, y)" queries.
class KeypointGrid {
 public:
  KeypointGrid() = default;
  KeypointGrid(std::span<const Keypoint> keypoints, int width, int height, int cell_size = 16);

  // Indices of keypoints with |dx|, |dy| <= radius and level in [min_level, max_level] (max_level < 0:
  // any level), appended to out after clearing it.
  void query(float x, float y, float radius, int min_level, int max_level, std::vector<int>& out) const;

 private:
  std::span<const Keypoint> keypoints_;
  int cell_size_ = 16, columns_ = 0, rows_ = 0;
  std::vector<int> cell_start_;  // CSR layout: indices_[cell_start_[c] .. cell_start_[c+1])
  std::vector<int> indices_;
};

struct Frame {
  std::size_t index = 0;
  double timestamp = 0.0;
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;
  std::vector<float> depth;        // metres, 0 = none
  std::vector<float> depth_sigma;  // metres, 0 = depth not usable
  std::vector<LandmarkId> landmarks;
  std::vector<bool> outlier;
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  KeypointGrid grid;  // refers to keypoints: rebuild after copying or moving the frame

  std::size_t size() const { return keypoints.size(); }
  void build_grid(int width, int height) { grid = KeypointGrid(keypoints, width, height); }
};

}  // namespace rgbl
