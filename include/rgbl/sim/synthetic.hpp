#pragma once
// A synthetic KITTI-like sequence with exact ground truth: a car drives down a textured street
// (rgbl/sim/scene.hpp) along a straight, curved or looping path (rgbl/sim/path.hpp); every frame
// has a rectified grey stereo pair (cameras 0/1), a colour pair (2/3), a 64-beam LiDAR scan, the
// exact depth image of one camera, the exact pose, calibration and a timestamp.
//
// Conventions are KITTI odometry's (SPEC section 1): poses are T_world_cam0 with the first pose the
// identity (the world is the first frame's rectified cam0: x right, y down, z forward); P_i = K [I | t_i]
// with all cameras sharing cam0's rotation; Tr = T_cam0_lidar; scans in the LiDAR frame (x forward,
// y left, z up) as float32 (x, y, z, reflectance); depth is camera z in metres, 0 = nothing hit.
// The same seed and options give the same bytes, whatever the thread count.

#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/sim/path.hpp"
#include "rgbl/sim/scene.hpp"

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace rgbl {

// KITTI odometry sequence 04's calibration (full size 1226x370): the template of the simulated rig.
KittiCalibration kitti_odometry_04_calibration();

struct SimLidarOptions {
  int beams = 64;                    // HDL-64E: upper half 1/3 deg apart, lower half spread to the bottom
  double max_elevation_deg = 2.0;
  double min_elevation_deg = -24.8;
  double azimuth_step_deg = 0.18;    // 2000 columns
  double min_range = 1.0;            // m; nearer returns are dropped
  double max_range = 120.0;          // m
  double range_noise_sigma = 0.02;   // m, Gaussian, along the beam; 0 = exact
  double dropout = 0.0;              // probability that a return is missing
  Eigen::Isometry3d T_cam0_lidar = kitti_odometry_04_calibration().T_cam0_lidar;  // KITTI 04's Tr

  void validate() const;
  // Elevation of each beam, degrees, top beam first.
  std::vector<double> elevations_deg() const;
};

// Inclusive range of frame indices.
struct FrameRange {
  int first = 0;
  int last = -1;
  bool contains(int i) const { return i >= first && i <= last; }
};

struct SyntheticOptions {
  std::uint64_t seed = 1;            // scene layout, textures' variety and all noise
  int frames = 50;
  PathOptions path{};
  double speed = 10.0;               // m/s (36 km/h: ~1 m per frame at 10 Hz)
  double frame_period = 0.1;         // s (10 Hz)
  // Image size; the intrinsics are KITTI 04's scaled by width / 1226 (and height / 370 for cy), so
  // 613x185 is exactly half of KITTI's resolution and 1226x370 is KITTI's own.
  int width = 613;
  int height = 185;
  double image_noise_sigma = 1.0;    // grey levels, Gaussian per pixel and channel; 0 = none
  int depth_camera = 2;              // camera (0 or 2) whose exact depth image is produced
  StreetOptions scene{};
  SimLidarOptions lidar{};
  std::optional<FrameRange> untextured;  // frames rendered with every surface plain (no texture)
  std::vector<int> dropped_scans;        // frames whose scan is empty (a LiDAR dropout)
  int threads = 2;                       // threads used to render one frame

  // Throws ConfigError naming the key, e.g. "frames", "width", "lidar.beams".
  void validate() const;
  // Arc length driven between frames, m.
  double step() const { return speed * frame_period; }
};

struct SyntheticFrame {
  int index = 0;
  double timestamp = 0.0;                                       // s
  Eigen::Isometry3d T_world_cam0 = Eigen::Isometry3d::Identity();
  // image_0 .. image_3: CV_8UC1 grey for 0/1, CV_8UC3 (BGR, OpenCV's order) for 2/3.
  std::array<cv::Mat, 4> images;
  std::vector<LidarPoint> scan;                                 // LiDAR frame
  cv::Mat_<float> depth;                                        // of options.depth_camera
};

struct SyntheticSequence {
  SyntheticOptions options;
  KittiCalibration calibration;  // with the image size filled in
  std::vector<SyntheticFrame> frames;
};

// Renders frames on demand: cheap to construct (lays out the path and scene), each frame rendered
// independently, so a long sequence is streamed to disk without being held in memory.
class SyntheticGenerator {
 public:
  explicit SyntheticGenerator(SyntheticOptions options);  // validates the options

  const SyntheticOptions& options() const { return options_; }
  const KittiCalibration& calibration() const { return calibration_; }
  const DrivePath& path() const { return *path_; }
  const StreetScene& scene() const { return *scene_; }
  int frame_count() const { return options_.frames; }

  Eigen::Isometry3d pose(int frame) const;  // T_world_cam0, exact
  double timestamp(int frame) const;

  // Everything for one frame. Thread-safe (const).
  SyntheticFrame render(int frame) const;
  // The parts, for tests and tools.
  cv::Mat render_image(int frame, int camera) const;
  cv::Mat_<float> render_depth(int frame, int camera) const;
  std::vector<LidarPoint> render_scan(int frame) const;

 private:
  Eigen::Isometry3d T_world_camera(int frame, int camera) const;

  SyntheticOptions options_;
  KittiCalibration calibration_;
  std::unique_ptr<DrivePath> path_;
  std::unique_ptr<StreetScene> scene_;
};

// All frames in memory (for tests: keep them few and small).
SyntheticSequence generate_sequence(const SyntheticOptions& options);

// Where a written sequence is.
struct KittiLayout {
  std::filesystem::path root;          // the dataset root holding sequences/ and poses/
  std::filesystem::path sequence_dir;  // root/sequences/NN
  std::filesystem::path poses_file;    // root/poses/NN.txt
};

KittiLayout kitti_layout(const std::filesystem::path& root, int sequence);

// Writes a sequence in KITTI odometry layout under `root`:
//   sequences/NN/{image_0,image_1,image_2,image_3}/NNNNNN.png, velodyne/NNNNNN.bin, calib.txt,
//   times.txt, depth/NNNNNN.png (uint16 = depth * 256 of options.depth_camera; 0 where nothing was hit
//   or beyond 255.99 m), sim.txt (the generator's options), and poses/NN.txt.
// Frames are rendered and written one by one; `on_frame(i)` is called after each. Throws rgbl::Error
// naming the file when a file cannot be written.
KittiLayout write_kitti(const SyntheticGenerator& generator, const std::filesystem::path& root, int sequence = 0,
                        const std::function<void(int)>& on_frame = {});
KittiLayout write_kitti(const SyntheticSequence& sequence, const std::filesystem::path& root, int sequence_number = 0);

}  // namespace rgbl
