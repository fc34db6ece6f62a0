#pragma once
// One tracked frame: keypoints, descriptors, depth per keypoint and a grid for radius queries.

#include "rgbl/features/matcher.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/features/types.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/map/map.hpp"

#include <Eigen/Geometry>

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace rgbl {

// Extracts keypoints and descriptors from a greyscale image. The tracker only needs this call, so any
// extractor (rgbl's ORB, OpenCV's, a user's) can be injected.
using FeatureExtractor =
    std::function<void(const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors)>;

// rgbl's ORB extractor (rgbl/features/orb.hpp) as a FeatureExtractor; copies share one extractor (so
// one call at a time). With a pool, pyramid levels are detected and described on its threads (the
// same features, bit for bit).
FeatureExtractor make_orb_extractor(const OrbOptions& options, std::shared_ptr<TaskPool> pool = nullptr);

struct Frame {
  std::size_t index = 0;
  double timestamp = 0.0;
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;
  std::vector<float> depth;        // metres, 0 = none
  std::vector<float> depth_sigma;  // metres, 0 = depth not usable
  // The depth source had a value here that the noise model refused (a depth edge under the kernel, too
  // uncertain): something was measured, just no single surface. Empty = none known.
  std::vector<bool> depth_refused;
  std::vector<LandmarkId> landmarks;
  std::vector<bool> outlier;
  // Keypoints on something moving against the scene: depth-consensus outliers of the frame-to-frame
  // motion and their depth-continuous neighbours (estimate_frame_motion). Empty = none known. They
  // are neither matched nor made landmarks.
  std::vector<bool> moving;
  // Landmarks on objects whose residuals erred together (TrackerOptions::object_test): where the
  // object was when it was mapped, no longer where it is. Erased when the frame's placement is taken.
  std::vector<LandmarkId> moved_landmarks;
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  // A subsample of the frame's LiDAR scan in its camera frame (null without a scan): a second
  // opinion on poses that the images leave ambiguous. Shared, so copies of the frame are cheap.
  std::shared_ptr<const ScanSample> scan;
  // False when the scan was taken apart from the image and no known motion could move it to the
  // image's time (a map's first frame: no velocity yet): its points are off by the distance driven in
  // between (0.17 m at KITTI's 17 ms and 10 m/s), too much to measure a keyframe's motion with.
  bool scan_at_image_time = true;
  FeatureGrid grid;  // radius queries over keypoints; rebuild after changing them

  std::size_t size() const { return keypoints.size(); }
  bool is_moving(std::size_t i) const { return !moving.empty() && moving[i]; }
  void build_grid(int width, int height) { grid = FeatureGrid(keypoints, width, height); }
};

}  // namespace rgbl
