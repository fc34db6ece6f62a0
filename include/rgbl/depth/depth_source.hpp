#pragma once
// The interface between "where depth comes from" and the tracker. A DepthSource turns one frame's
// sensor data (LiDAR scan, stereo pair, depth image, ...) into metric depth at keypoints, with what
// the tracker needs to weight it. Strategies are created by name (registry.hpp). This header and the
// registry are the target rgbl::depth_api, which the tracker links; the built-in sources are rgbl::depth.

#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>

namespace rgbl {

// One frame's raw sensor data, as a depth source consumes it. Views only: nothing is copied.
struct SensorFrame {
  std::size_t index = 0;
  double timestamp = 0.0;     // seconds
  cv::Mat image;              // tracked (rectified) camera image, CV_8UC1 or CV_8UC3
  cv::Mat image_right;        // rectified right image of a stereo pair; empty if none
  cv::Mat depth_image;        // a depth camera's or precomputed depth (CV_16UC1 or CV_32FC1); empty if none
  PointCloudView scan;        // LiDAR scan in the LiDAR frame; empty if none
  // When the scan faced forward, seconds, on the clock of `timestamp` (KITTI raw: velodyne_points/
  // timestamps.txt); unset when the dataset does not say. SystemOptions::scan_time_offset overrides it.
  std::optional<double> scan_timestamp;
  // The camera's motion from the scan's time to the image's: maps points in the camera frame at the
  // scan's time into the camera frame at the image's. A source that measures at the scan's time
  // projects the scan with it (System::scan_motion sets it; identity: the two are simultaneous).
  Eigen::Isometry3d T_image_scan = Eigen::Isometry3d::Identity();
};

// Depth at one keypoint. z == 0 means "no depth here".
struct KeypointDepth {
  float z = 0.0F;                   // camera depth (along the optical axis), metres
  float sample_distance_px = 0.0F;  // pixel distance to the real measurement the value came from
  float spread = 0.0F;              // max - min of valid depths under the kernel, metres (depth edge)
  // How fast the surface's depth changes across the image at the keypoint, metres per pixel (the
  // gradient's length); 0 when the source does not know it. A scan registered a little off the image
  // (calibration, sync) reads the depth that far away: the noise model weights that.
  float gradient = 0.0F;
};

// What a source reads from each frame besides the tracked image: a pipeline checks the dataset has
// it before the first frame, and loads no more than that (a scan also for loop closing).
struct DepthSourceNeeds {
  bool scan = false;         // a LiDAR scan
  bool right_image = false;  // the rectified right image of the tracked camera's stereo pair
  bool depth_image = false;  // a depth camera's (or precomputed) image in SensorFrame::depth_image
};

// What a source is created with besides its own options: the tracked camera as the dataset gives it.
struct DepthSourceContext {
  CameraCalibration calibration{};  // tracked (rectified) camera, with T_cam_lidar
  double stereo_baseline = 0.0;     // m, to the right camera of the pair; 0 without one

  void validate() const;  // the camera's intrinsics; throws ConfigError
};

class DepthSource {
 public:
  virtual ~DepthSource() = default;

  virtual std::string_view name() const = 0;

  // Per-frame work that does not depend on keypoints (e.g. projecting the scan). Throws on input the
  // source cannot use (e.g. no right image for the stereo source), naming what was expected. An empty
  // LiDAR scan (a dropout) is not an error: that frame has no depth.
  virtual void prepare(const SensorFrame& frame) = 0;

  // Depth at keypoint pixels, after prepare(). out.size() == pixels.size().
  virtual void sample(std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out) const = 0;

  // The dense (completed) depth map of the prepared frame, metres, 0 = none: for visualisation and
  // evaluation; may be computed on demand.
  virtual cv::Mat_<float> dense_depth() const = 0;

  // true when the depth is the scan's, measured at the scan's time rather than the image's, and
  // prepare() moves it by SensorFrame::T_image_scan.
  virtual bool measured_at_scan_time() const { return false; }
};

}  // namespace rgbl
