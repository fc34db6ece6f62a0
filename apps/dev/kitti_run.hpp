#pragma once
// Development harness shared by rgbl_track_kitti and the tracking tests: runs the System with the
// `lidar` depth source and rgbl's ORB extractor on a KITTI sequence; KITTI pose reading, ATE and drift.
// Header-only on purpose: it is not part of the library.

#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/depth/depth_source.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/projection.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/tracking/system.hpp"

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace rgbl::dev {

inline std::vector<Eigen::Isometry3d> read_kitti_poses(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ParseError(file, 0, "a KITTI pose file");
  std::vector<Eigen::Isometry3d> poses;
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    std::istringstream s(line);
    Matrix34d M;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (!(s >> M(r, c))) throw ParseError(file, n, "12 numbers");
      }
    }
    poses.push_back(isometry_from_3x4(M));
  }
  return poses;
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 == 1 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

struct RunSummary {
  int frames = 0, tracked = 0, lost = 0, keyframes = 0;
  double ate_rmse = 0.0, drift_percent = 0.0, path_length = 0.0, scale_ratio = 0.0;
  double median_depth_ms = 0.0, median_extraction_ms = 0.0, median_tracking_ms = 0.0, median_mapping_ms = 0.0;
  double median_front_ms = 0.0;  // depth + extraction + tracking
  double median_total_ms = 0.0, mean_total_ms = 0.0, mean_mapping_ms = 0.0;
  std::vector<Eigen::Isometry3d> estimate;  // T_world_cam0 per frame (world = first cam0)
  std::vector<Eigen::Isometry3d> truth;
};

struct RunOptions {
  int camera = 2;
  int frames = -1;  // all
  bool verbose = false;  // one line per frame on stdout
  SystemOptions system;
  OrbOptions orb;
  std::string depth = "lidar";  // or "stereo" (SGBM on the pair camera / camera + 1)
};

// Runs the System on a KITTI odometry sequence folder (.../sequences/NN) with LiDAR depth.
inline RunSummary run_kitti_sequence(const std::filesystem::path& sequence, const RunOptions& options) {
  const std::string name = sequence.filename().string();
  const auto image_dir = sequence / ("image_" + std::to_string(options.camera));
  std::vector<std::filesystem::path> images;
  for (const auto& e : std::filesystem::directory_iterator(image_dir)) images.push_back(e.path());
  std::sort(images.begin(), images.end());
  if (options.frames > 0 && static_cast<int>(images.size()) > options.frames) {
    images.resize(static_cast<std::size_t>(options.frames));
  }
  if (images.empty()) throw Error("no images in " + image_dir.string());
  const cv::Mat first = cv::imread(images.front().string(), cv::IMREAD_GRAYSCALE);
  const KittiCalibration kitti = read_kitti_odometry_calibration(sequence / "calib.txt", first.cols, first.rows);
  const CameraCalibration calibration = kitti.camera(options.camera);
  std::vector<double> times;
  {
    std::ifstream in(sequence / "times.txt");
    double t = 0.0;
    while (in >> t) times.push_back(t);
  }
  DepthSourceSettings depth_settings;
  depth_settings.calibration = calibration;
  const bool stereo = options.depth == "stereo";
  if (!stereo && options.depth != "lidar") throw ConfigError("depth", "lidar or stereo");
  const auto right_dir = sequence / ("image_" + std::to_string(options.camera + 1));
  if (stereo) depth_settings.stereo_baseline = kitti.baseline(options.camera, options.camera + 1);
  auto orb = std::make_shared<OrbExtractor>(options.orb);
  SystemOptions system_options = options.system;
  if (stereo && system_options.depth_noise.sigma_quadratic == 0.0) {
    // Stereo depth error grows with z^2: sigma_z = z^2 / (fx * baseline) * sigma_disparity (0.5 px).
    system_options.depth_noise.sigma_quadratic = 0.5 / (calibration.camera.fx * depth_settings.stereo_baseline);
  }
  System system(system_options, calibration,
                stereo ? make_stereo_source(depth_settings) : make_lidar_source(depth_settings),
                [orb](const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors) {
                  orb->extract(gray, keypoints, descriptors);
                });
  RunSummary summary;
  std::vector<double> depth_ms, extraction_ms, tracking_ms, mapping_ms, front_ms, total_ms;
  std::vector<LidarPoint> scan;
  for (std::size_t i = 0; i < images.size(); ++i) {
    SensorFrame frame;
    frame.index = i;
    frame.timestamp = i < times.size() ? times[i] : static_cast<double>(i) * 0.1;
    frame.image = cv::imread(images[i].string(), cv::IMREAD_GRAYSCALE);
    const auto stem = images[i].stem().string();
    if (stereo) {
      frame.image_right = cv::imread((right_dir / images[i].filename()).string(), cv::IMREAD_GRAYSCALE);
    } else {
      read_kitti_scan(sequence / "velodyne" / (stem + ".bin"), scan);
      frame.scan = scan;
    }
    const TrackResult r = system.track(frame);
    if (options.verbose) {
      const Eigen::Vector3d t = r.T_world_cam.translation();
      std::printf("frame %3zu %-8s kf %d inliers %4d kp %4d depth %4d  t %8.3f %8.3f %8.3f  ms %.1f/%.1f/%.1f/%.1f\n",
                  i, to_string(r.state), r.keyframe ? 1 : 0, r.inliers, r.keypoints, r.keypoints_with_depth,
                  t.x(), t.y(), t.z(), r.timing.depth_ms, r.timing.extraction_ms, r.timing.tracking_ms,
                  r.timing.mapping_ms);
    }
    ++summary.frames;
    if (r.state == TrackState::Ok) ++summary.tracked;
    if (r.state == TrackState::Lost) ++summary.lost;
    summary.keyframes += r.keyframe ? 1 : 0;
    depth_ms.push_back(r.timing.depth_ms);
    extraction_ms.push_back(r.timing.extraction_ms);
    tracking_ms.push_back(r.timing.tracking_ms);
    mapping_ms.push_back(r.timing.mapping_ms);
    front_ms.push_back(r.timing.depth_ms + r.timing.extraction_ms + r.timing.tracking_ms);
    total_ms.push_back(r.timing.total_ms);
  }
  system.finish();
  summary.median_depth_ms = median(depth_ms);
  summary.median_extraction_ms = median(extraction_ms);
  summary.median_tracking_ms = median(tracking_ms);
  summary.median_mapping_ms = median(mapping_ms);
  summary.median_front_ms = median(front_ms);
  summary.median_total_ms = median(total_ms);
  double sum = 0.0;
  for (const double t : total_ms) sum += t;
  summary.mean_total_ms = sum / static_cast<double>(total_ms.size());
  double mapping_sum = 0.0;
  for (const double t : mapping_ms) mapping_sum += t;
  summary.mean_mapping_ms = mapping_sum / static_cast<double>(mapping_ms.size());

  // Poses in the cam0 frame: T_world_cam0 = T_world_cam * T_cam_cam0, world = first cam0.
  const Eigen::Isometry3d T_cam_cam0 = calibration.T_cam_cam0;
  const auto trajectory = system.trajectory();
  for (const auto& p : trajectory) summary.estimate.push_back(T_cam_cam0.inverse() * p.T_world_cam * T_cam_cam0);

  const auto poses_file = sequence.parent_path().parent_path() / "poses" / (name + ".txt");
  if (std::filesystem::exists(poses_file)) {
    const auto gt = read_kitti_poses(poses_file);
    const std::size_t n = std::min(gt.size(), summary.estimate.size());
    summary.truth.assign(gt.begin(), gt.begin() + static_cast<std::ptrdiff_t>(n));
    Eigen::Matrix3Xd est(3, n), ref(3, n);
    for (std::size_t i = 0; i < n; ++i) {
      est.col(static_cast<Eigen::Index>(i)) = summary.estimate[i].translation();
      ref.col(static_cast<Eigen::Index>(i)) = gt[i].translation();
      if (i > 0) summary.path_length += (gt[i].translation() - gt[i - 1].translation()).norm();
    }
    const Eigen::Matrix4d A = Eigen::umeyama(est, ref, false);
    double se = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d a = A.topLeftCorner<3, 3>() * est.col(static_cast<Eigen::Index>(i)) + A.topRightCorner<3, 1>();
      se += (a - ref.col(static_cast<Eigen::Index>(i))).squaredNorm();
    }
    summary.ate_rmse = std::sqrt(se / static_cast<double>(n));
    // End-point drift: error of the last pose relative to the first (both start at identity).
    const Eigen::Isometry3d E = (summary.estimate.front().inverse() * summary.estimate[n - 1]).inverse() *
                                (gt.front().inverse() * gt[n - 1]);
    summary.drift_percent = summary.path_length > 0.0 ? 100.0 * E.translation().norm() / summary.path_length : 0.0;
    const double est_len = (summary.estimate[n - 1].translation() - summary.estimate.front().translation()).norm();
    const double gt_len = (gt[n - 1].translation() - gt.front().translation()).norm();
    summary.scale_ratio = gt_len > 0.0 ? est_len / gt_len : 0.0;
  }
  return summary;
}

inline void write_kitti_trajectory(const std::filesystem::path& file, const std::vector<Eigen::Isometry3d>& poses) {
  std::ofstream out(file);
  if (!out) throw ParseError(file, 0, "a writable file");
  char buffer[64];
  for (const auto& T : poses) {
    const Matrix34d M = to_3x4(T);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::snprintf(buffer, sizeof(buffer), "%.9e", M(r, c));
        out << buffer << (r == 2 && c == 3 ? '\n' : ' ');
      }
    }
  }
}

}  // namespace rgbl::dev
