#pragma once
// Map export as an ASCII PLY: coloured points (landmarks) and camera poses drawn as small pyramids
// (apex at the optical centre, base `camera_size` metres ahead along z), readable by MeshLab,
// CloudCompare and Open3D.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>

namespace rgbl {

struct PlyOptions {
  double camera_size = 0.5;                              // m
  std::array<std::uint8_t, 3> camera_rgb{255, 0, 0};     // colour of the camera pyramids
  std::array<std::uint8_t, 3> point_rgb{200, 200, 200};  // colour of points when none is given

  void validate() const;
};

// colours_rgb is empty or has one entry per point. Camera poses are T_world_cam. Writes to a temporary
// file renamed at the end; throws Error naming the file when it cannot be written.
void write_ply(const std::filesystem::path& file, std::span<const Eigen::Vector3d> points,
               std::span<const std::array<std::uint8_t, 3>> colours_rgb,
               std::span<const Eigen::Isometry3d> T_world_cams, const PlyOptions& options = {});

}  // namespace rgbl
