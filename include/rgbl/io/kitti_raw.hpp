#pragma once
// Ground truth of KITTI raw drives from the OXTS (GPS/IMU) packets, computed as the raw devkit does:
// a Mercator projection scaled by the first packet's latitude gives metric x (east), y (north), z (up);
// roll, pitch, yaw give R = Rz(yaw) * Ry(pitch) * Rx(roll) of the IMU; poses are made relative to the
// first packet.

#include <Eigen/Geometry>

#include <filesystem>
#include <span>
#include <vector>

namespace rgbl {

struct OxtsPacket {
  double lat = 0.0, lon = 0.0, alt = 0.0;                   // deg, deg, m
  double roll = 0.0, pitch = 0.0, yaw = 0.0;                // rad
  double vn = 0.0, ve = 0.0, vf = 0.0, vl = 0.0, vu = 0.0;  // m/s
};

// Reads one oxts/data/*.txt (30 numbers; the first 11 are kept). Throws ParseError naming the file.
OxtsPacket read_oxts_packet(const std::filesystem::path& file);

// T_imu0_imu for every packet (the first is the identity), metres.
std::vector<Eigen::Isometry3d> oxts_imu_poses(std::span<const OxtsPacket> packets);

// Reads a calib_imu_to_velo.txt or calib_velo_to_cam.txt ("R: 9 numbers", "T: 3 numbers") as the
// transform it describes (T_velo_imu, T_cam_velo). R must be a rotation to 1e-4 and T at most 100 m.
Eigen::Isometry3d read_kitti_rigid_transform(const std::filesystem::path& file);

// A raw sensor's timestamps.txt ("YYYY-MM-DD hh:mm:ss.fraction" per line) in seconds since 1970,
// strictly increasing. Throws ParseError naming the file and line.
std::vector<double> read_kitti_raw_timestamps(const std::filesystem::path& file);

}  // namespace rgbl
