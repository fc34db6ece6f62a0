#include "rgbl/tracking/frame_builder.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"

#include <opencv2/imgproc.hpp>

namespace rgbl {

FrameBuilder::FrameBuilder(const CameraCalibration& calibration, const DepthNoiseModel& noise,
                           std::unique_ptr<DepthSource> depth, FeatureExtractor extractor,
                           std::shared_ptr<TaskPool> pool, const ScanSampleOptions& scan_sample)
    : calibration_(calibration), noise_(noise), depth_(std::move(depth)), extractor_(std::move(extractor)),
      pool_(std::move(pool)), scan_sample_(scan_sample) {
  scan_sample_.validate();
  if (!depth_) throw ConfigError("depth", "a depth source");
  if (!extractor_) throw ConfigError("extractor", "a feature extractor");
}

PreparedFrame FrameBuilder::build(const SensorFrame& sensor) { return build(sensor, true); }

PreparedFrame FrameBuilder::build_ahead(const SensorFrame& sensor) {
  return build(sensor, false);
}

// whole: also the scan sample and the depth of a source that measures at the scan's time (the part
// finish() does)
PreparedFrame FrameBuilder::build(const SensorFrame& sensor, bool whole) {
  const bool with_depth = whole || !depth_->measured_at_scan_time();
  Stopwatch wall;
  PreparedFrame out;
  out.frame.index = sensor.index;
  out.frame.timestamp = sensor.timestamp;

  double prepare_ms = 0.0;
  const auto prepare = [&] {
    Stopwatch t;
    if (whole) sample_scan_points(sensor, out.frame);
    if (with_depth) depth_->prepare(sensor);
    prepare_ms = t.elapsed_ms();
  };
  // the preparation beside extraction when there is a second thread; its exception after both.
  // Ahead of a LiDAR source's finish() there is nothing to prepare (whole implies with_depth).
  TaskPool::Task prepared;
  if (with_depth) {
    if (pool_ && pool_->threads() > 1) {
      prepared = pool_->submit(prepare);
    } else {
      prepare();
    }
  }
  extract(sensor, out);
  prepared.wait();

  Stopwatch sampling;
  if (with_depth) sample_depth(out);
  out.depth_ms = prepare_ms + sampling.elapsed_ms();
  out.critical_ms = wall.elapsed_ms();
  return out;
}

void FrameBuilder::finish(PreparedFrame& prepared, const SensorFrame& sensor) {
  Stopwatch wall;
  sample_scan_points(sensor, prepared.frame);
  if (depth_->measured_at_scan_time()) {
    depth_->prepare(sensor);
    sample_depth(prepared);
  }
  const double ms = wall.elapsed_ms();
  prepared.depth_ms += ms;
  prepared.critical_ms += ms;
}

void FrameBuilder::sample_scan_points(const SensorFrame& sensor, Frame& frame) const {
  if (sensor.scan.empty()) return;
  frame.scan = std::make_shared<const ScanSample>(
      sample_scan(sensor.scan, sensor.T_image_scan * calibration_.T_cam_lidar, scan_sample_));
}

void FrameBuilder::extract(const SensorFrame& sensor, PreparedFrame& out) {
  Stopwatch extraction;
  Frame& frame = out.frame;
  // A grey input is used in place, never kept in gray_: a later colour frame of the same size would
  // be converted into the caller's (by then perhaps freed) buffer.
  const cv::Mat* gray = &sensor.image;
  if (sensor.image.channels() == 3) {
    cv::cvtColor(sensor.image, gray_, cv::COLOR_BGR2GRAY);
    gray = &gray_;
  }
  extractor_(*gray, frame.keypoints, frame.descriptors);
  frame.build_grid(calibration_.camera.width, calibration_.camera.height);
  out.extraction_ms = extraction.elapsed_ms();
}

void FrameBuilder::sample_depth(PreparedFrame& out) {
  Frame& frame = out.frame;
  const std::size_t n = frame.keypoints.size();
  pixels_.resize(n);
  depths_.assign(n, KeypointDepth{});
  for (std::size_t i = 0; i < n; ++i) pixels_[i] = Eigen::Vector2f(frame.keypoints[i].x, frame.keypoints[i].y);
  depth_->sample(pixels_, depths_);
  frame.depth.resize(n);
  frame.depth_sigma.resize(n);
  frame.depth_refused.assign(n, false);
  out.keypoints_with_depth = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const KeypointDepth& d = depths_[i];
    const double sigma = d.z > 0.0F ? noise_.sigma(d.z, d.sample_distance_px, d.spread, calibration_.camera.fx, d.gradient) : 0.0;
    frame.depth[i] = sigma > 0.0 ? d.z : 0.0F;
    frame.depth_sigma[i] = static_cast<float>(sigma);
    frame.depth_refused[i] = d.z > 0.0F && !(sigma > 0.0);
    out.keypoints_with_depth += sigma > 0.0 ? 1 : 0;
  }
}

}  // namespace rgbl
