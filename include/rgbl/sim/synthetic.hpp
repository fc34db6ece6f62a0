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
#include "rgbl/sim/actors.hpp"
#include "rgbl/sim/path.hpp"
#include "rgbl/sim/scene.hpp"

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/matx.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
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
  // Leaf penetration: returns from foliage land this much deeper on average (one-sided, half-normal
  // with this mean), on top of range_noise_sigma; 0 = foliage is as solid as a wall.
  double foliage_penetration = 0.0;  // m
  // The intrinsic calibration's error: each beam fires at its nominal elevation plus an error (all
  // beams' elevation_offset_deg, and a Gaussian of beam_elevation_sigma_deg drawn once per beam and
  // seed), while its points are computed with the nominal one, as a real LiDAR's are. KITTI's HDL-64
  // is known for one of about 0.2 deg in all beams (docs/accuracy.md, "What lengthens 04's path").
  // 0 = exact beams.
  double elevation_offset_deg = 0.0;
  double beam_elevation_sigma_deg = 0.0;
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

// Light: ambient plus a sun (Lambertian). Cast shadows trace a ray towards the sun from every sample;
// a tree's crown lets light through its leaf gaps (dappled shadows), a hedge or a wall does not.
struct LightOptions {
  Eigen::Vector3d sun_direction{0.35, -0.85, 0.40};  // towards the sun, world (y down); normalised in use
  double ambient = 0.7;
  double sun = 0.4;
  bool cast_shadows = false;
  double leaf_gap = 0.35;  // share of a crown's area that lets sunlight through

  void validate() const;  // keys "light.*"
};

// From `frame` on, the camera's gain is multiplied by `gain` (an auto exposure's step).
struct ExposureStep {
  int frame = 0;
  double gain = 1.0;
};

struct SyntheticOptions {
  std::string scenario;              // the scenario these options came from (rgbl/sim/scenarios.hpp), for the record
  std::uint64_t seed = 1;            // scene layout, textures' variety and all noise
  int frames = 50;
  PathOptions path{};
  double speed = 10.0;               // m/s at time 0 (36 km/h: ~1 m per frame at 10 Hz)
  std::vector<SpeedPhase> speed_phases;  // the camera's accelerations after time 0; none = constant speed
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
  std::vector<Actor> actors;             // moving vehicles (rgbl/sim/actors.hpp)
  LightOptions light{};
  // Camera gain per frame: the product of the steps reached, times 1 + drift * sin(2 pi frame / period).
  std::vector<ExposureStep> exposure_steps;
  double exposure_drift = 0.0;           // relative amplitude of a slow gain oscillation
  double exposure_drift_period = 80.0;   // frames
  // Motion blur: each pixel averages the image along its own motion (camera and actors) during the
  // exposure, centred on the frame's time; 0 = sharp.
  double exposure_time = 0.0;            // s
  // Optics: a Gaussian point spread, pixels (KITTI's images are not pixel-sharp); 0 = none.
  double lens_blur_sigma = 0.0;
  // Tone: grey levels are stretched by this factor about `contrast_pivot` (before the noise), like a
  // camera's response that puts the sky near white and the shadows near black; 1 = linear.
  double contrast = 1.0;
  double contrast_pivot = 90.0;  // grey level that stays where it is
  std::array<bool, 4> cameras{true, true, true, true};  // which images render() makes (the rest stay empty)
  bool render_depth = true;                             // whether render() makes the exact depth image
  int threads = 2;                       // threads used to render one frame

  // Throws ConfigError naming the key, e.g. "frames", "width", "lidar.beams".
  void validate() const;
  // Arc length driven between frames at the initial speed, m.
  double step() const { return speed * frame_period; }
  // The camera's speed profile and the arc length driven by the last frame.
  SpeedProfile speed_profile() const { return SpeedProfile(speed, speed_phases, "speed_phases"); }
  double driven_length() const { return speed_profile().distance((frames - 1) * frame_period); }
};

struct SyntheticFrame {
  int index = 0;
  double timestamp = 0.0;                                       // s
  Eigen::Isometry3d T_world_cam0 = Eigen::Isometry3d::Identity();
  // image_0 .. image_3: CV_8UC1 grey for 0/1, CV_8UC3 (BGR, OpenCV's order) for 2/3; empty when
  // options.cameras leaves the camera out.
  std::array<cv::Mat, 4> images;
  std::vector<LidarPoint> scan;                                 // LiDAR frame
  cv::Mat_<float> depth;                                        // of options.depth_camera (if render_depth)
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
  double arc_length(int frame) const;        // m driven along the path by this frame
  Eigen::Isometry3d pose_at(double t) const; // T_world_cam0 at any time t (s)
  double exposure_gain(int frame) const;     // the camera gain (1 = the look of the defaults)

  // The actors' boxes at this frame's time, and the first hit of a ray with the street and them:
  // an object id >= scene().objects().size() is actor_boxes(frame)[id - scene().objects().size()].
  std::vector<SceneObject> actor_boxes(int frame) const;
  std::optional<RayHit> intersect(int frame, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_max) const;
  // Length in pixels of each pixel's motion during the exposure (the motion blur's extent).
  cv::Mat_<float> blur_extent(int frame, int camera) const;

  // Everything for one frame. Thread-safe (const).
  SyntheticFrame render(int frame) const;
  // The parts, for tests and tools.
  cv::Mat render_image(int frame, int camera) const;
  cv::Mat_<float> render_depth(int frame, int camera) const;
  std::vector<LidarPoint> render_scan(int frame) const;

 private:
  Eigen::Isometry3d T_world_camera(int frame, int camera) const;
  // Per pixel, the image motion (du, dv) from the start to the end of the exposure.
  cv::Mat_<cv::Vec2f> exposure_flow(int frame, int camera) const;

  SyntheticOptions options_;
  KittiCalibration calibration_;
  std::unique_ptr<DrivePath> path_;
  std::unique_ptr<StreetScene> scene_;
};

// Makes options.path a `laps`-lap loop whose perimeter is the distance driven over options.frames:
// the corners shrink (down to the generator's 12 m) so that a short run still closes its loop.
// Throws ConfigError("--frames") naming the frames needed when they cannot close the laps.
void fit_loop(SyntheticOptions& options, int laps);

// All frames in memory (for tests: keep them few and small).
SyntheticSequence generate_sequence(const SyntheticOptions& options);

// Where a written sequence is.
struct KittiLayout {
  std::filesystem::path root;          // the dataset root holding sequences/ and poses/
  std::filesystem::path sequence_dir;  // root/sequences/NN
  std::filesystem::path poses_file;    // root/poses/NN.txt
};

KittiLayout kitti_layout(const std::filesystem::path& root, int sequence);

// Writes a sequence in KITTI odometry layout under `root` (folders only for the cameras and depth rendered):
//   sequences/NN/{image_0,image_1,image_2,image_3}/NNNNNN.png, velodyne/NNNNNN.bin, calib.txt,
//   times.txt, depth/NNNNNN.png (uint16 = depth * 256 of options.depth_camera; 0 where nothing was hit
//   or beyond 255.99 m), sim.txt (the generator's options), and poses/NN.txt.
// Frames are rendered and written one by one; `on_frame(i)` is called after each. Throws rgbl::Error
// naming the file when a file cannot be written, or before writing anything when sequences/NN or
// poses/NN.txt already exists (it never overwrites a dataset).
KittiLayout write_kitti(const SyntheticGenerator& generator, const std::filesystem::path& root, int sequence = 0,
                        const std::function<void(int)>& on_frame = {});
KittiLayout write_kitti(const SyntheticSequence& sequence, const std::filesystem::path& root, int sequence_number = 0);

}  // namespace rgbl
