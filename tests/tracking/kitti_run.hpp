#pragma once
// Runs the System on the real KITTI excerpt through the library's own loader and metrics, as
// `rgbl run` does, for the tracking acceptance tests.

#include "support/sensor_frame.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/io/sequence.hpp"
#include "rgbl/tracking/system.hpp"

#include <filesystem>
#include <memory>
#include <vector>

namespace rgbl::test {

struct SequenceRun {
  std::size_t frames = 0, tracked = 0;  // tracked: reported ok
  std::size_t with_pose = 0;              // ok or weak: a pose was estimated
  std::vector<Eigen::Isometry3d> estimate;  // T_world_cam0, world = first cam0 (as poses/NN.txt)
  std::vector<Eigen::Isometry3d> truth;
  double ate_rmse = 0.0, drift_percent = 0.0;
};

inline SequenceRun run_sequence(const std::filesystem::path& dir, int camera, std::size_t frames,
                                const SystemOptions& options = {}) {
  const auto sequence = open_kitti_odometry(dir);
  const CameraCalibration calibration = sequence->calibration().camera(camera);
  DepthSourceContext depth;
  depth.calibration = calibration;
  auto orb = std::make_shared<OrbExtractor>();
  System system(options, calibration, make_lidar_source({}, depth),
                [orb](const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors) {
                  orb->extract(gray, keypoints, descriptors);
                });
  SequenceRun run;
  run.frames = std::min(frames, sequence->size());
  for (std::size_t i = 0; i < run.frames; ++i) {
    const FrameInput input = sequence->load(i);
    SensorFrame frame = sensor_frame(input, camera);
    frame.index = i;
    const TrackState state = system.track(frame).state;
    run.tracked += state == TrackState::Ok ? 1 : 0;
    run.with_pose += has_pose(state) ? 1 : 0;
  }
  system.finish();
  const Eigen::Isometry3d T_cam_cam0 = calibration.T_cam_cam0;
  for (const auto& pose : system.trajectory()) {
    run.estimate.push_back(T_cam_cam0.inverse() * pose.T_world_cam * T_cam_cam0);
  }
  const auto& gt = sequence->ground_truth()->poses;
  run.truth.assign(gt.begin(), gt.begin() + static_cast<std::ptrdiff_t>(run.estimate.size()));
  run.ate_rmse = absolute_trajectory_error(run.estimate, run.truth).translation.rmse;
  run.drift_percent = end_point_drift(run.estimate, run.truth).percent;
  return run;
}

}  // namespace rgbl::test
