#pragma once
// Trajectory files in the two formats the evaluation tools read:
// - KITTI: one row-major 3x4 matrix [R | t] per frame (12 numbers), T_world_cam0, every frame;
// - TUM:   `t tx ty tz qx qy qz qw` per pose (timestamp in seconds, quaternion Hamilton, w last).
// Writers print every number with the shortest representation that reads back to the same double,
// and write to a temporary file renamed at the end, so a failed run never leaves a file that looks
// complete. Readers skip blank lines and lines starting with '#', and throw ParseError naming the
// file and line on anything else that is not a pose.

#include <Eigen/Geometry>

#include <cstddef>
#include <filesystem>
#include <istream>
#include <span>
#include <utility>
#include <vector>

namespace rgbl {

// Poses with their timestamps (seconds); timestamps may be empty for KITTI files.
struct Trajectory {
  std::vector<double> timestamps;
  std::vector<Eigen::Isometry3d> poses;

  std::size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
};

void write_kitti_trajectory(const std::filesystem::path& file, std::span<const Eigen::Isometry3d> poses);
std::vector<Eigen::Isometry3d> read_kitti_trajectory(const std::filesystem::path& file);

// timestamps.size() must equal poses.size().
void write_tum_trajectory(const std::filesystem::path& file, const Trajectory& trajectory);
Trajectory read_tum_trajectory(const std::filesystem::path& file);
// The same from a stream already open (a pipe or a FIFO can be read only once); `file` names it in errors.
std::vector<Eigen::Isometry3d> read_kitti_trajectory(std::istream& in, const std::filesystem::path& file);
Trajectory read_tum_trajectory(std::istream& in, const std::filesystem::path& file);

// Pairs (i, j) with |a[i] - b[j]| <= max_difference, chosen greedily by smallest difference as TUM's
// associate.py does; each index used at most once; sorted by i. Both lists must be sorted ascending.
std::vector<std::pair<std::size_t, std::size_t>> associate_timestamps(std::span<const double> a,
                                                                      std::span<const double> b, double max_difference);

}  // namespace rgbl
