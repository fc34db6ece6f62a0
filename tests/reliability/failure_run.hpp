#pragma once
// Runs the System (LiDAR depth, rgbl's ORB) on frames of the real KITTI excerpt with injected
// failures: black images, dropped scans, jumps in the frame sequence. Header-only test support.
#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/io/trajectory_io.hpp"
#include "rgbl/tracking/system.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rgbl::test {

struct Step {
  std::size_t frame = 0;  // KITTI frame read from disk (and its ground truth)
  bool black = false;     // replace the image by zeros
  bool drop_scan = false;
  std::optional<std::size_t> index;  // SensorFrame index (timestamp 0.1 s x index) if not `frame`
  std::optional<std::size_t> image_from;  // KITTI frame whose image is fed instead of `frame`'s
};

struct Outcome {
  std::vector<rgbl::TrackResult> results;
  std::vector<rgbl::TrajectoryPose> trajectory;
  std::vector<Eigen::Isometry3d> truth;  // T_world_cam0 of the frames fed
};

inline Outcome run(const std::filesystem::path& sequence, const std::vector<Step>& steps, bool threaded = false,
                   rgbl::SystemOptions options = {}) {
  const auto name = [](std::size_t i) { return fmt::format("{:06}", i); };
  const cv::Mat first = rgbl::read_image_file(sequence / "image_0" / (name(0) + ".png"), rgbl::ImageMode::grey);
  const auto kitti = rgbl::read_kitti_odometry_calibration(sequence / "calib.txt", first.cols, first.rows);
  rgbl::DepthSourceContext depth;
  depth.calibration = kitti.camera(0);
  auto orb = std::make_shared<rgbl::OrbExtractor>();
  options.threaded_mapping = threaded;
  rgbl::System system(options, depth.calibration, rgbl::make_lidar_source({}, depth),
                      [orb](const cv::Mat& g, std::vector<rgbl::Keypoint>& k, std::vector<rgbl::Descriptor>& d) {
                        orb->extract(g, k, d);
                      });
  const auto poses = rgbl::read_kitti_trajectory(sequence.parent_path().parent_path() / "poses" /
                                                 (sequence.filename().string() + ".txt"));
  Outcome out;
  std::vector<rgbl::LidarPoint> scan;
  for (const Step& step : steps) {
    rgbl::SensorFrame frame;
    frame.index = step.index.value_or(step.frame);
    frame.timestamp = 0.1 * static_cast<double>(frame.index);
    frame.image = rgbl::read_image_file(sequence / "image_0" / (name(step.image_from.value_or(step.frame)) + ".png"),
                                        rgbl::ImageMode::grey);
    REQUIRE(!frame.image.empty());
    if (step.black) frame.image = cv::Mat::zeros(frame.image.size(), CV_8UC1);
    scan.clear();
    if (!step.drop_scan) rgbl::read_kitti_scan(sequence / "velodyne" / (name(step.frame) + ".bin"), scan);
    frame.scan = scan;
    out.results.push_back(system.track(frame));
    out.truth.push_back(poses.at(step.frame));
  }
  system.finish();
  out.trajectory = system.trajectory();
  return out;
}

inline std::vector<Step> frames(std::size_t first, std::size_t last) {
  std::vector<Step> steps;
  for (std::size_t i = first; i <= last; ++i) {
    Step step;
    step.frame = i;
    steps.push_back(step);
  }
  return steps;
}

// Frames first..last, then a jump to to_first..to_last (forwards or back). renumber: the fed indices,
// hence the timestamps, run on without a gap (0, 1, 2, ...): only the images jump.
inline std::vector<Step> jump(std::size_t first, std::size_t last, std::size_t to_first, std::size_t to_last,
                              bool renumber = false) {
  auto steps = frames(first, last);
  const auto after = frames(to_first, to_last);
  steps.insert(steps.end(), after.begin(), after.end());
  if (renumber) {
    for (std::size_t i = 0; i < steps.size(); ++i) steps[i].index = i;
  }
  return steps;
}

// Every fed frame is in the trajectory, in order, with the state track() reported and a finite pose.
inline void check_complete(const Outcome& o) {
  REQUIRE(o.trajectory.size() == o.results.size());
  for (std::size_t i = 0; i < o.results.size(); ++i) {
    INFO("frame " << o.results[i].frame_index);
    CHECK(o.trajectory[i].frame_index == o.results[i].frame_index);
    CHECK(o.trajectory[i].state == o.results[i].state);
    CHECK(o.trajectory[i].T_world_cam.matrix().allFinite());
  }
}

inline std::string states(const Outcome& o) {
  std::string s;
  for (const auto& r : o.results) s += fmt::format("{}:{} ", r.frame_index, rgbl::to_string(r.state));
  return s;
}

// Translation error of frame k relative to frame 0 against ground truth (both start at frame 0).
inline double relative_error(const Outcome& o, std::size_t k) {
  const Eigen::Isometry3d est = o.trajectory.front().T_world_cam.inverse() * o.trajectory[k].T_world_cam;
  const Eigen::Isometry3d gt = o.truth.front().inverse() * o.truth[k];
  return (est.translation() - gt.translation()).norm();
}


}  // namespace rgbl::test
