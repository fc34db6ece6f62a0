#pragma once
// The part of a frame's work that needs nothing but the frame's own sensor data: keypoints,
// descriptors, metric depth at each keypoint with its noise, the radius-query grid. It depends on no
// tracking state, so the next frame can be built while this one is tracked (System::track with a
// PreparedFrame), and the result is the same whichever thread built it.

#include "rgbl/backend/depth_noise.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/depth/depth_source.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/tracking/frame.hpp"

#include <memory>
#include <vector>

namespace rgbl {

struct PreparedFrame {
  Frame frame;  // no pose yet
  int keypoints_with_depth = 0;
  double depth_ms = 0.0;       // the depth source's preparation and keypoint sampling
  double extraction_ms = 0.0;  // colour conversion and feature extraction
  // Wall time the tracking thread spent on this frame before tracking it: the whole build when built
  // on that thread, the wait for it when built ahead on another.
  double critical_ms = 0.0;
};

// One frame in flight at a time: the depth source holds the frame it prepared until the next build.
class FrameBuilder {
 public:
  // With a pool of more than one thread the depth source prepares the frame while features are
  // extracted (and the extractor may use the pool too, see make_orb_extractor).
  // scan_sample: what the frame keeps of its LiDAR scan (Frame::scan).
  FrameBuilder(const CameraCalibration& calibration, const DepthNoiseModel& noise, std::unique_ptr<DepthSource> depth,
               FeatureExtractor extractor, std::shared_ptr<TaskPool> pool = nullptr,
               const ScanSampleOptions& scan_sample = {});

  // Throws what the depth source throws on input it cannot use (e.g. no right image for stereo).
  PreparedFrame build(const SensorFrame& sensor);
  // build() in two steps, for a frame whose scan is moved by the motion tracked up to the previous
  // frame (SensorFrame::T_image_scan, System::scan_motion). build_ahead: what does not depend on that
  // motion (the features; the depth too unless the source measures at the scan's time), a function
  // of the frame alone. finish: the rest, with the motion set, on the calling thread. Together they
  // give what build() gives for the same sensor frame.
  PreparedFrame build_ahead(const SensorFrame& sensor);
  void finish(PreparedFrame& prepared, const SensorFrame& sensor);

  const DepthSource& depth_source() const { return *depth_; }

 private:
  PreparedFrame build(const SensorFrame& sensor, bool whole);
  void extract(const SensorFrame& sensor, PreparedFrame& out);
  void sample_scan_points(const SensorFrame& sensor, Frame& frame) const;
  void sample_depth(PreparedFrame& out);

  CameraCalibration calibration_;
  DepthNoiseModel noise_;
  std::unique_ptr<DepthSource> depth_;
  FeatureExtractor extractor_;
  std::shared_ptr<TaskPool> pool_;
  ScanSampleOptions scan_sample_;
  cv::Mat gray_;
  std::vector<Eigen::Vector2f> pixels_;
  std::vector<KeypointDepth> depths_;
};

}  // namespace rgbl
