// KITTI odometry and raw loaders, and the format detection.
#include "file_sequence.hpp"
#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/io/kitti_raw.hpp"
#include "rgbl/io/sequence.hpp"
#include "text.hpp"

#include <Eigen/SVD>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <functional>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <string>

namespace rgbl {
namespace {

namespace fs = std::filesystem;

fs::path normalised_dir(const fs::path& dir, std::string_view expected) {
  require_input_folder(dir, expected);
  auto path = dir.lexically_normal();
  if (!path.has_filename()) path = path.parent_path();  // "seq/04/" -> "seq/04"
  return path;
}

// Number of frames: one past the highest index found in any sensor folder.
std::size_t frame_count(const std::vector<fs::path>& dirs, std::string_view ext_png, std::string_view ext_bin,
                        const std::vector<bool>& is_scan) {
  std::size_t count = 0;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const auto indices = detail::numbered_files(dirs[k], is_scan[k] ? ext_bin : ext_png);
    if (!indices.empty()) count = std::max(count, indices.back() + 1);
  }
  return count;
}

// Frame times must order the frames: a repeated or earlier time would give a trajectory that no
// evaluation (TUM's format, interpolation) accepts.
void require_increasing(const fs::path& file, std::size_t line_no, double t, double previous,
                        std::size_t previous_line) {
  if (!(t > previous)) {
    throw ParseError(file, line_no,
                     fmt::format("timestamp {} is not after the one on line {} ({}); expected strictly increasing "
                                 "times, one per frame",
                                 t, previous_line, previous));
  }
}

// "2011-09-26 13:08:24.973999360" -> seconds since 1970-01-01 (the clock's own time zone).
double parse_raw_timestamp(std::string_view text, const fs::path& file, std::size_t line_no) {
  const auto tokens = detail::split(text);
  // Fixed layout: digits at every position except the separators.
  const auto digits = [](std::string_view t, std::initializer_list<std::size_t> separators) {
    for (std::size_t k = 0; k < t.size(); ++k) {
      const bool separator = std::find(separators.begin(), separators.end(), k) != separators.end();
      if (!separator && !std::isdigit(static_cast<unsigned char>(t[k]))) return false;
    }
    return true;
  };
  const auto number = [](std::string_view t) {
    int v = 0;
    std::from_chars(t.data(), t.data() + t.size(), v);
    return v;
  };
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  double second = 0.0;
  bool ok = tokens.size() == 2 && tokens[0].size() == 10 && tokens[1].size() >= 8 && tokens[0][4] == '-' &&
            tokens[0][7] == '-' && tokens[1][2] == ':' && tokens[1][5] == ':' && digits(tokens[0], {4, 7}) &&
            digits(tokens[1].substr(0, 5), {2});
  if (ok) {
    year = number(tokens[0].substr(0, 4));
    month = number(tokens[0].substr(5, 2));
    day = number(tokens[0].substr(8, 2));
    hour = number(tokens[1].substr(0, 2));
    minute = number(tokens[1].substr(3, 2));
    ok = detail::parse_double(tokens[1].substr(6), second) && month >= 1 && month <= 12 && day >= 1 && day <= 31 &&
         hour < 24 && minute < 60 && second >= 0.0 && second < 61.0;
  }
  if (!ok) throw ParseError(file, line_no, "expected a timestamp 'YYYY-MM-DD hh:mm:ss.fraction'");
  // Days from civil (proleptic Gregorian).
  const int y = year - (month <= 2 ? 1 : 0);
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (month + (month > 2 ? -3 : 9)) + 2) / 5 + day - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  const double days = static_cast<double>(era) * 146097.0 + doe - 719468.0;
  return days * 86400.0 + hour * 3600.0 + minute * 60.0 + second;
}

std::vector<double> read_raw_timestamps(const fs::path& file, bool strictly_increasing) {
  auto in = detail::open_for_reading(file, "KITTI raw timestamps, one per line");
  std::vector<double> values;
  std::string line;
  std::size_t line_no = 0, previous_line = 0;
  while (detail::read_line(in, line, line_no)) {
    if (detail::split(line).empty()) continue;
    const double t = parse_raw_timestamp(line, file, line_no);
    if (strictly_increasing && !values.empty()) require_increasing(file, line_no, t, values.back(), previous_line);
    values.push_back(t);
    previous_line = line_no;
  }
  return values;
}

void check_count(const fs::path& file, std::size_t rows, std::size_t frames, std::string_view what) {
  if (rows != frames) {
    throw ParseError(
        file, 0, fmt::format("has {} {}, expected {} (one per frame found in the sensor folders)", rows, what, frames));
  }
}

}  // namespace

std::vector<double> read_kitti_times(const fs::path& times_txt) {
  constexpr std::string_view kWhat = "one timestamp (seconds) per line";
  auto in = detail::open_for_reading(times_txt, kWhat);
  std::vector<double> values;
  std::string line;
  std::size_t line_no = 0, previous_line = 0;
  while (detail::read_line(in, line, line_no)) {
    const auto tokens = detail::split(line);
    if (tokens.empty()) continue;
    double t = 0.0;
    if (tokens.size() != 1 || !detail::parse_double(tokens[0], t) || !std::isfinite(t)) {
      throw ParseError(times_txt, line_no, fmt::format("expected {}", kWhat));
    }
    if (!values.empty()) require_increasing(times_txt, line_no, t, values.back(), previous_line);
    values.push_back(t);
    previous_line = line_no;
  }
  return values;
}

std::vector<double> read_kitti_raw_timestamps(const fs::path& file) { return read_raw_timestamps(file, true); }

std::unique_ptr<Sequence> open_kitti_odometry(const fs::path& sequence_dir, const LoadOptions& options) {
  const fs::path dir = normalised_dir(
      sequence_dir, "a KITTI odometry sequence folder with calib.txt, times.txt, image_0..3/, velodyne/");
  detail::SequenceTable table;
  table.format = DatasetFormat::kitti;
  table.name = dir.filename().string();
  table.path = dir;
  table.calibration = read_kitti_odometry_calibration(dir / "calib.txt");
  table.calibration_file = dir / "calib.txt";

  std::vector<fs::path> dirs;
  std::vector<bool> is_scan;
  std::error_code ec;
  for (std::size_t c = 0; c < 4; ++c) {
    const auto d = dir / fmt::format("image_{}", c);
    table.sensors.cameras[c] = fs::is_directory(d, ec);
    if (table.sensors.cameras[c]) {
      dirs.push_back(d);
      is_scan.push_back(false);
    }
  }
  table.sensors.lidar = fs::is_directory(dir / "velodyne", ec);
  if (table.sensors.lidar) {
    dirs.push_back(dir / "velodyne");
    is_scan.push_back(true);
  }
  const std::size_t count = frame_count(dirs, ".png", ".bin", is_scan);
  if (count == 0) {
    throw ParseError(dir, 0, "no frames found (expected image_0..3/NNNNNN.png and/or velodyne/NNNNNN.bin)");
  }
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    detail::require_frames(dirs[k], count, 6, is_scan[k] ? ".bin" : ".png");
  }
  const auto times_file = dir / "times.txt";
  const auto times = read_kitti_times(times_file);
  check_count(times_file, times.size(), count, "timestamps");

  table.frames.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    auto& f = table.frames[i];
    f.timestamp = times[i];
    for (std::size_t c = 0; c < 4; ++c) {
      if (table.sensors.cameras[c]) f.images[c] = dir / fmt::format("image_{}", c) / fmt::format("{:06}.png", i);
    }
    if (table.sensors.lidar) f.scan = dir / "velodyne" / fmt::format("{:06}.bin", i);
  }

  const auto poses_file = dir.parent_path().parent_path() / "poses" / (table.name + ".txt");
  if (fs::exists(poses_file, ec)) {
    require_input_file(poses_file, "a KITTI trajectory: 12 numbers per line");  // read_kitti_trajectory takes pipes
    auto poses = read_kitti_trajectory(poses_file);
    if (poses.size() < count) {
      throw ParseError(poses_file, 0,
                       fmt::format("has {} poses, fewer than the {} frames of {}", poses.size(), count, dir.string()));
    }
    if (poses.size() > count) {
      table.notes.push_back(fmt::format("ground truth: using the first {} of the {} poses in {}", count, poses.size(),
                                        poses_file.string()));
      poses.resize(count);
    }
    Trajectory gt;
    gt.timestamps = times;
    gt.poses = std::move(poses);
    for (std::size_t i = 0; i < count; ++i) table.frames[i].T_world_cam0 = gt.poses[i];
    table.ground_truth = std::move(gt);
  }
  detail::set_image_sizes(table);
  for (const auto& note : table.notes) logger()->info("{}", note);
  return detail::make_file_sequence(std::move(table), options);
}

OxtsPacket read_oxts_packet(const fs::path& file) {
  auto in = detail::open_for_reading(file, "an OXTS packet: 30 numbers on one line");
  std::string line;
  std::size_t line_no = 0;
  while (detail::read_line(in, line, line_no)) {
    if (!detail::split(line).empty()) break;
  }
  const auto tokens = detail::split(line);
  if (tokens.size() != 30) {
    throw ParseError(file, line_no, fmt::format("expected 30 numbers (OXTS packet), found {} fields", tokens.size()));
  }
  double v[11];
  for (std::size_t k = 0; k < 11; ++k) {
    if (!detail::parse_double(tokens[k], v[k]) || !std::isfinite(v[k])) {
      throw ParseError(file, line_no, fmt::format("field {} '{}' is not a finite number", k + 1, tokens[k]));
    }
  }
  if (std::abs(v[0]) > 90.0 || std::abs(v[1]) > 180.0) {
    throw ParseError(file, line_no, "latitude/longitude out of range (expected degrees)");
  }
  return {v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10]};
}

std::vector<Eigen::Isometry3d> oxts_imu_poses(std::span<const OxtsPacket> packets) {
  std::vector<Eigen::Isometry3d> poses;
  if (packets.empty()) return poses;
  constexpr double kEarthRadius = 6378137.0;  // m, as in the devkit
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double scale = std::cos(packets.front().lat * kDeg);
  Eigen::Isometry3d T_imu0_world = Eigen::Isometry3d::Identity();
  poses.reserve(packets.size());
  for (std::size_t i = 0; i < packets.size(); ++i) {
    const auto& p = packets[i];
    const Eigen::Vector3d t(scale * p.lon * kDeg * kEarthRadius,
                            scale * kEarthRadius * std::log(std::tan((90.0 + p.lat) * std::numbers::pi / 360.0)),
                            p.alt);
    const Eigen::Matrix3d R =
        (Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(p.pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(p.roll, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Eigen::Isometry3d T_world_imu = make_isometry(R, t);
    if (i == 0) T_imu0_world = T_world_imu.inverse();
    poses.push_back(T_imu0_world * T_world_imu);
  }
  return poses;
}

Eigen::Isometry3d read_kitti_rigid_transform(const fs::path& file) {
  auto in = detail::open_for_reading(file, "a KITTI calibration with 'R: 9 numbers' and 'T: 3 numbers'");
  std::optional<Eigen::Matrix3d> R;
  std::optional<Eigen::Vector3d> t;
  std::string line;
  std::size_t line_no = 0, R_line = 0, t_line = 0;
  while (detail::read_line(in, line, line_no)) {
    const auto tokens = detail::split(line);
    if (tokens.empty() || (tokens[0] != "R:" && tokens[0] != "T:")) continue;
    const std::size_t n = tokens[0] == "R:" ? 9 : 3;
    std::size_t& seen = n == 9 ? R_line : t_line;
    if (seen != 0) {
      throw ParseError(file, line_no, fmt::format("'{}' given twice (lines {} and {}); expected one line per key",
                                                  tokens[0].substr(0, 1), seen, line_no));
    }
    seen = line_no;
    if (tokens.size() != n + 1) {
      throw ParseError(file, line_no, fmt::format("expected {} numbers after '{}'", n, tokens[0]));
    }
    std::vector<double> v(n);
    for (std::size_t k = 0; k < n; ++k) {
      if (!detail::parse_double(tokens[k + 1], v[k]) || !std::isfinite(v[k])) {
        throw ParseError(file, line_no, fmt::format("'{}' is not a finite number", tokens[k + 1]));
      }
    }
    if (n == 9) {
      R = Eigen::Matrix3d();
      for (int k = 0; k < 9; ++k) (*R)(k / 3, k % 3) = v[static_cast<std::size_t>(k)];
    } else {
      t = Eigen::Vector3d(v[0], v[1], v[2]);
    }
  }
  if (!R) throw ParseError(file, 0, "expected a line 'R: ' followed by 9 numbers");
  if (!t) throw ParseError(file, 0, "expected a line 'T: ' followed by 3 numbers");
  // to 1e-4: the files' 7-digit rotations are orthonormal to ~1e-7
  if (const double error = rotation_error(*R); !(error <= 1e-4)) {
    throw ParseError(file, R_line,
                     fmt::format("expected 'R' to hold a rotation matrix (orthonormal, det +1), found R^T R - I or "
                                 "det R - 1 off by {:.2g}",
                                 error));
  }
  if (!(t->norm() <= 100.0)) {
    throw ParseError(file, t_line, fmt::format("expected 'T' to hold a translation of at most 100 m, found {:g} m",
                                               t->norm()));
  }
  return make_isometry(*R, *t);
}

std::unique_ptr<Sequence> open_kitti_raw(const fs::path& drive_dir, const LoadOptions& options) {
  const fs::path dir = normalised_dir(
      drive_dir,
      "a KITTI raw drive folder (<date>_drive_NNNN_sync) with image_0x/data, velodyne_points/data, oxts/data");
  const fs::path date_dir = dir.parent_path();
  detail::SequenceTable table;
  table.format = DatasetFormat::kitti_raw;
  table.name = dir.filename().string();
  table.path = dir;
  table.calibration = read_kitti_raw_calibration(date_dir);
  table.calibration_file = date_dir / "calib_cam_to_cam.txt";

  std::vector<fs::path> dirs;
  std::vector<bool> is_scan;
  std::error_code ec;
  fs::path time_source;
  for (std::size_t c = 0; c < 4; ++c) {
    const auto sensor = dir / fmt::format("image_{:02}", c);
    table.sensors.cameras[c] = fs::is_directory(sensor / "data", ec);
    if (!table.sensors.cameras[c]) continue;
    dirs.push_back(sensor / "data");
    is_scan.push_back(false);
    if (time_source.empty()) time_source = sensor / "timestamps.txt";
  }
  table.sensors.lidar = fs::is_directory(dir / "velodyne_points" / "data", ec);
  if (table.sensors.lidar) {
    dirs.push_back(dir / "velodyne_points" / "data");
    is_scan.push_back(true);
    if (time_source.empty()) time_source = dir / "velodyne_points" / "timestamps.txt";
  }
  const std::size_t count = frame_count(dirs, ".png", ".bin", is_scan);
  if (count == 0) {
    throw ParseError(dir, 0, "no frames found (expected image_0x/data/NNNNNNNNNN.png and/or velodyne_points/data)");
  }
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    detail::require_frames(dirs[k], count, 10, is_scan[k] ? ".bin" : ".png");
  }
  const auto times = read_kitti_raw_timestamps(time_source);
  check_count(time_source, times.size(), count, "timestamps");

  table.frames.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    auto& f = table.frames[i];
    f.timestamp = times[i];
    for (std::size_t c = 0; c < 4; ++c) {
      if (table.sensors.cameras[c]) {
        f.images[c] = dir / fmt::format("image_{:02}", c) / "data" / fmt::format("{:010}.png", i);
      }
    }
    if (table.sensors.lidar) f.scan = dir / "velodyne_points" / "data" / fmt::format("{:010}.bin", i);
  }
  // The cameras fire as the LiDAR faces forward, and their timestamps come later (16.9 ms in drive
  // 2011_09_26_0009): the LiDAR's own times let the tracker move its depth to the image's time.
  const auto scan_times_file = dir / "velodyne_points" / "timestamps.txt";
  if (table.sensors.lidar && scan_times_file != time_source && fs::exists(scan_times_file, ec)) {
    const auto scan_times = read_raw_timestamps(scan_times_file, false);
    check_count(scan_times_file, scan_times.size(), count, "timestamps");
    // beyond kMaxScanAge a glitch of the log, not a latency: that frame's depth is taken as
    // simultaneous, and the run goes on
    std::vector<std::size_t> apart;
    for (std::size_t i = 0; i < count; ++i) {
      if (std::abs(times[i] - scan_times[i]) <= kMaxScanAge) {
        table.frames[i].scan_timestamp = scan_times[i];
      } else {
        apart.push_back(i);
      }
    }
    if (!apart.empty()) {
      table.notes.push_back(fmt::format("{}: {} scan time(s) more than 1 s from the image's ({}), first at frame {} "
                                        "({:.3f} s); those frames' LiDAR depth is taken as simultaneous",
                                        scan_times_file.string(), apart.size(), time_source.string(), apart.front(),
                                        times[apart.front()] - scan_times[apart.front()]));
    }
  }

  const auto oxts_dir = dir / "oxts" / "data";
  if (fs::is_directory(oxts_dir, ec)) {
    const auto imu_to_velo = date_dir / "calib_imu_to_velo.txt";
    if (!fs::exists(imu_to_velo, ec)) {
      table.notes.push_back(fmt::format("no ground truth: {} is missing (needed to express the OXTS poses in cam0)",
                                        imu_to_velo.string()));
    } else {
      detail::require_frames(oxts_dir, count, 10, ".txt");
      std::vector<OxtsPacket> packets;
      packets.reserve(count);
      for (std::size_t i = 0; i < count; ++i)
        packets.push_back(read_oxts_packet(oxts_dir / fmt::format("{:010}.txt", i)));
      const auto T_imu0_imu = oxts_imu_poses(packets);
      // Rectified cam0 from the IMU: R_rect_00 * T_cam_velo (already in T_cam0_lidar) * T_velo_imu.
      Eigen::Isometry3d T_cam0_imu = table.calibration.T_cam0_lidar * read_kitti_rigid_transform(imu_to_velo);
      // The calibration's 7-digit rotations are orthonormal to ~1e-7 only: project onto SO(3) so that
      // the inverse is exact and the first pose is the identity.
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(T_cam0_imu.linear(), Eigen::ComputeFullU | Eigen::ComputeFullV);
      T_cam0_imu.linear() = svd.matrixU() * svd.matrixV().transpose();
      const Eigen::Isometry3d T_imu_cam0 = T_cam0_imu.inverse();
      std::vector<Eigen::Isometry3d> T_world_imu = T_imu0_imu;
      // The OXTS unit logs at its own clock, jittering by +-10 ms around the camera's: the pose of a
      // frame is the one at its camera timestamp, interpolated on SE(3) between the two nearest
      // packets (a 1.3 m step at 13 m/s moves 13 cm in 10 ms).
      const auto oxts_times_file = dir / "oxts" / "timestamps.txt";
      if (fs::exists(oxts_times_file, ec)) {
        // the OXTS clock only places the packets: out of order falls back to packet by packet below
        const auto oxts_times = read_raw_timestamps(oxts_times_file, false);
        check_count(oxts_times_file, oxts_times.size(), count, "timestamps");
        if (count >= 2 && std::is_sorted(oxts_times.begin(), oxts_times.end(), std::less_equal<>())) {
          for (std::size_t i = 0; i < count; ++i) {
            const auto next = std::upper_bound(oxts_times.begin(), oxts_times.end(), times[i]);
            const auto k = static_cast<std::size_t>(
                std::clamp<std::ptrdiff_t>(next - oxts_times.begin() - 1, 0, static_cast<std::ptrdiff_t>(count) - 2));
            const double s = (times[i] - oxts_times[k]) / (oxts_times[k + 1] - oxts_times[k]);
            T_world_imu[i] = interpolate(T_imu0_imu[k], T_imu0_imu[k + 1], s);
          }
        } else {
          table.notes.push_back(fmt::format("{}: not strictly increasing; ground truth taken packet by packet",
                                            oxts_times_file.string()));
        }
      }
      // the world is the first frame's rectified cam0
      const Eigen::Isometry3d T_imu_world = T_world_imu.front().inverse();
      Trajectory gt;
      gt.timestamps = times;
      for (std::size_t i = 0; i < count; ++i) {
        gt.poses.push_back(T_cam0_imu * T_imu_world * T_world_imu[i] * T_imu_cam0);
        table.frames[i].T_world_cam0 = gt.poses.back();
      }
      table.ground_truth = std::move(gt);
    }
  }
  detail::set_image_sizes(table);
  for (const auto& note : table.notes) logger()->warn("{}", note);
  return detail::make_file_sequence(std::move(table), options);
}

DatasetFormat parse_dataset_format(std::string_view name) {
  if (name == "auto") return DatasetFormat::automatic;
  if (name == "kitti") return DatasetFormat::kitti;
  if (name == "kitti-raw") return DatasetFormat::kitti_raw;
  if (name == "tum") return DatasetFormat::tum;
  throw ConfigError("format", "one of auto, kitti, kitti-raw, tum");
}

std::string_view to_string(DatasetFormat format) {
  switch (format) {
    case DatasetFormat::automatic:
      return "auto";
    case DatasetFormat::kitti:
      return "kitti";
    case DatasetFormat::kitti_raw:
      return "kitti-raw";
    case DatasetFormat::tum:
      return "tum";
  }
  return "unknown";
}

std::unique_ptr<Sequence> open_sequence(const fs::path& dir, DatasetFormat format, const LoadOptions& options) {
  if (format == DatasetFormat::automatic) {
    std::error_code ec;
    // an unreadable folder would look like one of an unknown format
    require_input_folder(dir, "a KITTI odometry sequence, KITTI raw drive or TUM RGB-D folder");
    if (fs::exists(dir / "calib.txt", ec) && fs::exists(dir / "times.txt", ec)) {
      format = DatasetFormat::kitti;
    } else if (fs::is_directory(dir / "oxts", ec) || fs::is_directory(dir / "velodyne_points", ec) ||
               fs::is_directory(dir / "image_00", ec)) {
      format = DatasetFormat::kitti_raw;
    } else if (fs::exists(dir / "rgb.txt", ec)) {
      format = DatasetFormat::tum;
    } else {
      throw ParseError(dir, 0,
                       "cannot tell the dataset format (expected calib.txt + times.txt for KITTI odometry, "
                       "oxts/ or velodyne_points/ for a KITTI raw drive, rgb.txt for TUM RGB-D); use --format");
    }
  }
  switch (format) {
    case DatasetFormat::kitti:
      return open_kitti_odometry(dir, options);
    case DatasetFormat::kitti_raw:
      return open_kitti_raw(dir, options);
    case DatasetFormat::tum:
      return open_tum_rgbd(dir, {}, options);
    case DatasetFormat::automatic:
      break;
  }
  throw ConfigError("format", "one of auto, kitti, kitti-raw, tum");
}

std::vector<LoadProblem> check_sequence(const Sequence& sequence,
                                        const std::function<void(std::size_t, std::size_t)>& progress) {
  const SensorSet& sensors = sequence.sensors();
  LoadOptions none;
  none.cameras = {false, false, false, false};
  none.lidar = false;
  none.depth = false;
  std::vector<LoadOptions> loads;  // one sensor each
  for (std::size_t c = 0; c < sensors.cameras.size(); ++c) {
    if (!sensors.cameras[c]) continue;
    loads.push_back(none);
    loads.back().cameras[c] = true;
  }
  if (sensors.lidar) {
    loads.push_back(none);
    loads.back().lidar = true;
  }
  if (sensors.depth) {
    loads.push_back(none);
    loads.back().depth = true;
  }
  std::vector<LoadProblem> problems;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    for (const LoadOptions& load : loads) {
      try {
        (void)sequence.load(i, load);
      } catch (const Error& e) {
        problems.push_back({i, e.what()});
      }
    }
    if (progress) progress(i + 1, sequence.size());
  }
  return problems;
}

}  // namespace rgbl
