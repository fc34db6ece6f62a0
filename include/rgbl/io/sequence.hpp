#pragma once
// Datasets as a sequence of frames. Opening a sequence checks the whole folder once (every frame's
// files present, counts of timestamps and poses matching, calibration readable, image sizes), so a
// half-downloaded dataset fails at the start with the name of the missing or wrong file, not after
// an hour of processing. load(i) then reads one frame's files and checks them.

#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/camera.hpp"
#include "rgbl/io/frame_input.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rgbl {

enum class DatasetFormat { automatic, kitti, kitti_raw, tum };

// "auto", "kitti", "kitti-raw", "tum"; throws ConfigError("format", ...) otherwise.
DatasetFormat parse_dataset_format(std::string_view name);
std::string_view to_string(DatasetFormat format);

// Which sensors a dataset provides.
struct SensorSet {
  std::array<bool, 4> cameras{};  // see FrameInput::images
  bool lidar = false;
  bool depth = false;
};

// What load() reads; sensors the dataset lacks are skipped silently (see Sequence::sensors()).
struct LoadOptions {
  std::array<bool, 4> cameras{true, true, true, true};
  bool lidar = true;
  bool depth = true;
};

class Sequence {
 public:
  virtual ~Sequence() = default;

  virtual DatasetFormat format() const = 0;
  virtual const std::string& name() const = 0;
  virtual const std::filesystem::path& path() const = 0;
  virtual std::size_t size() const = 0;
  virtual const SensorSet& sensors() const = 0;
  // Rectified cameras and T_cam0_lidar, with the image sizes of the cameras present.
  virtual const KittiCalibration& calibration() const = 0;
  virtual double timestamp(std::size_t index) const = 0;
  // T_world_cam0 with the frame timestamps. KITTI: one pose per frame. TUM: only the frames inside
  // the ground truth's time span (match by timestamp). nullopt when the dataset has none.
  virtual const std::optional<Trajectory>& ground_truth() const = 0;
  // What the loader decided on its own (e.g. "using the first 51 of 271 poses"), for the user.
  virtual const std::vector<std::string>& notes() const = 0;

  // Reads frame `index` (< size()). Safe to call from another thread concurrently with the const
  // accessors (ReadAhead does). Throws ParseError naming the file that is missing, unreadable,
  // corrupt or of the wrong size.
  virtual FrameInput load(std::size_t index) const = 0;
  // The same with other sensors than the sequence was opened with (e.g. only the scan).
  virtual FrameInput load(std::size_t index, const LoadOptions& options) const = 0;
};

// KITTI odometry: sequences/NN with image_0..3/, velodyne/, calib.txt, times.txt; ground truth from
// ../../poses/NN.txt when present (poses may be more than the frames: the first size() are used).
std::unique_ptr<Sequence> open_kitti_odometry(const std::filesystem::path& sequence_dir,
                                              const LoadOptions& options = {});

// A KITTI odometry times.txt: one time in seconds per line (blank lines skipped), finite and strictly
// increasing. Throws ParseError naming the file and line.
std::vector<double> read_kitti_times(const std::filesystem::path& times_txt);

// KITTI raw drive (<date>/<date>_drive_XXXX_sync): image_0x/data, velodyne_points/data, oxts/data,
// the calib_*.txt one level up. Ground truth of rectified cam0 from the OXTS packets (see kitti_raw.hpp).
std::unique_ptr<Sequence> open_kitti_raw(const std::filesystem::path& drive_dir, const LoadOptions& options = {});

struct TumOptions {
  // Intrinsics of the RGB camera; when unset they are taken from the folder name (freiburg1/2/3,
  // the published values without distortion) or the ROS default 525/525/319.5/239.5.
  std::optional<PinholeCamera> camera;
  double depth_factor = 5000.0;       // depth PNG value per metre
  double max_time_difference = 0.02;  // s, rgb/depth association
  double max_ground_truth_gap = 0.1;  // s, longest gap between ground-truth samples to interpolate over

  void validate() const;
};

// TUM RGB-D: rgb.txt, depth.txt (optional), groundtruth.txt (optional), rgb/ and depth/ images.
// Frames are the rgb images that have a depth image within max_time_difference (all rgb images
// when there is no depth.txt).
std::unique_ptr<Sequence> open_tum_rgbd(const std::filesystem::path& dir, const TumOptions& tum = {},
                                        const LoadOptions& options = {});

// Detects the layout when format is automatic: calib.txt + times.txt -> kitti, oxts/ or
// velodyne_points/ -> kitti-raw, rgb.txt -> tum.
std::unique_ptr<Sequence> open_sequence(const std::filesystem::path& dir,
                                        DatasetFormat format = DatasetFormat::automatic,
                                        const LoadOptions& options = {});

// A file of a sequence that does not load: the frame and the loader's message (which names the file).
struct LoadProblem {
  std::size_t frame = 0;
  std::string message;
};

// Loads every file of every frame, one sensor at a time, so that every bad file is listed, not only
// the first of a frame. `progress(done, total)` is called after each frame when given.
std::vector<LoadProblem> check_sequence(const Sequence& sequence,
                                        const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace rgbl
