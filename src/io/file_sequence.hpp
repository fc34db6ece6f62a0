#pragma once
// The one Sequence implementation (internal): every loader resolves the dataset layout into a table
// of per-frame files, checked once at opening; load() only reads and checks them.

#include "rgbl/io/sequence.hpp"

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace rgbl::detail {

struct FrameFiles {
  double timestamp = 0.0;
  std::array<std::filesystem::path, 4> images;  // empty path: camera absent
  std::filesystem::path scan;
  std::optional<double> scan_timestamp;  // when the scan faced forward, on the clock of `timestamp`
  std::filesystem::path depth;
  std::optional<Eigen::Isometry3d> T_world_cam0;
};

struct SequenceTable {
  DatasetFormat format = DatasetFormat::automatic;
  std::string name;
  std::filesystem::path path;
  KittiCalibration calibration;
  // the file of the intrinsics, checked against the image sizes; empty: not checked (TUM's are fixed
  // published values or TumOptions', which validate() checks)
  std::filesystem::path calibration_file;
  SensorSet sensors;
  std::vector<FrameFiles> frames;
  std::optional<Trajectory> ground_truth;
  std::vector<std::string> notes;
  double depth_factor = 0.0;      // depth PNG units per metre
  bool grey_from_colour = false;  // TUM: camera 0 is the grey conversion of camera 2
};

std::unique_ptr<Sequence> make_file_sequence(SequenceTable table, const LoadOptions& options);

// Reads an image (grey when `grey`), throwing ParseError naming the file when it cannot be decoded.
cv::Mat read_image(const std::filesystem::path& file, bool grey);

// Fills table.calibration's sizes for the cameras present from their first image; when the
// calibration already has a size for a camera (raw), the first image must match it. Then checks the
// intrinsics against the sizes (PinholeCamera::implausibility), naming table.calibration_file.
void set_image_sizes(SequenceTable& table);

// Throws ParseError naming the first missing file of frames 0..count-1 in dir (name = zero-padded
// index of `digits` digits + extension).
void require_frames(const std::filesystem::path& dir, std::size_t count, int digits, std::string_view extension);

}  // namespace rgbl::detail
