#pragma once
// Projection of a LiDAR scan into a sparse depth image of one camera (SPEC section 2).
// Depth is camera z in metres; 0 means "no return". Where several points fall on one pixel the
// nearest wins (a z-buffer), so background never overwrites foreground.

#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/se3.hpp"

#include <opencv2/core/mat.hpp>

namespace rgbl {

struct ProjectionOptions {
  float min_depth = 5.0F;    // m; points at z <= min_depth are dropped (paper: 5 m)
  float max_depth = 200.0F;  // m; points at z >= max_depth are dropped (paper: 200 m)

  void validate() const;
};

// Writes the sparse depth of `cloud` into `depth`, which must already have the camera's size (its
// contents are overwritten; its buffer is reused). P_img_lidar is the full 3x4 projection of LiDAR
// points into the image, including the camera's translation (CameraCalibration::P_img_lidar()).
// Non-finite points are skipped. Returns the number of pixels filled.
int project_to_depth(PointCloudView cloud, const Matrix34d& P_img_lidar, const ProjectionOptions& options,
                     cv::Mat_<float>& depth);

// Convenience overload that allocates the image.
cv::Mat_<float> project_to_depth(PointCloudView cloud, const Matrix34d& P_img_lidar, int width, int height,
                                 const ProjectionOptions& options = {});

}  // namespace rgbl
