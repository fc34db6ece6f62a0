#include "rgbl/geometry/calibration.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <Eigen/LU>
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace rgbl {
namespace {

struct Entry {
  std::vector<double> values;
  std::size_t line = 0;
};

// "KEY: v1 v2 ..." lines. Lines whose values are not all numbers (e.g. raw's calib_time) are kept with
// an empty value list so that asking for them gives a precise message.
struct KeyValueFile {
  std::filesystem::path path;
  std::map<std::string, Entry, std::less<>> entries;

  // The values of `key`, which must be `count` finite numbers.
  const Entry& get(const std::string& key, std::size_t count) const {
    const auto it = entries.find(key);
    if (it == entries.end()) {
      throw ParseError(path, 0, fmt::format("expected a line '{}: ' followed by {} numbers", key, count));
    }
    if (it->second.values.size() != count) {
      throw ParseError(path, it->second.line,
                       fmt::format("expected {} numbers after '{}:', found {}", count, key,
                                   it->second.values.size()));
    }
    for (const double v : it->second.values) {
      if (!std::isfinite(v)) {
        throw ParseError(path, it->second.line, fmt::format("expected finite numbers after '{}:'", key));
      }
    }
    return it->second;
  }
};

bool parse_double(std::string_view token, double& out) {
  const auto* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, out);
  return result.ec == std::errc() && result.ptr == end;
}

KeyValueFile parse_key_value(std::istream& in, const std::filesystem::path& path) {
  KeyValueFile file{path, {}};
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);  // UTF-8 byte order mark
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) {
      throw ParseError(path, line_no, "expected 'KEY: values', found no ':'");
    }
    std::string key = line.substr(0, colon);
    key.erase(0, key.find_first_not_of(" \t"));
    key.erase(key.find_last_not_of(" \t") + 1);
    Entry entry;
    entry.line = line_no;
    std::string_view rest(line);
    rest.remove_prefix(colon + 1);
    bool numeric = true;
    while (!rest.empty()) {
      const auto start = rest.find_first_not_of(" \t");
      if (start == std::string_view::npos) break;
      rest.remove_prefix(start);
      const auto stop = std::min(rest.find_first_of(" \t"), rest.size());
      double value = 0.0;
      if (!parse_double(rest.substr(0, stop), value)) {
        numeric = false;
        break;
      }
      entry.values.push_back(value);
      rest.remove_prefix(stop);
    }
    if (!numeric) entry.values.clear();
    if (const auto it = file.entries.find(key); it != file.entries.end()) {
      throw ParseError(path, line_no, fmt::format("'{}' given twice (lines {} and {}); expected one line per key", key,
                                                  it->second.line, line_no));
    }
    file.entries.emplace(std::move(key), std::move(entry));
  }
  return file;
}

std::ifstream open_calibration(const std::filesystem::path& path) {
  return open_input_file(path, "a KITTI calibration file");
}

template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> row_major(const std::vector<double>& v) {
  Eigen::Matrix<double, Rows, Cols> m;
  for (int r = 0; r < Rows; ++r)
    for (int c = 0; c < Cols; ++c) m(r, c) = v[static_cast<std::size_t>(r * Cols + c)];
  return m;
}

// A rectified projection K [I | t]: plausible intrinsics (see PinholeCamera::implausibility; the size
// when known), no skew or rotation, and a camera within kMaxOffset of cam0.
void check_projection(const KeyValueFile& file, const std::string& key, const Matrix34d& P, int width, int height) {
  constexpr double kMaxOffset = 100.0;  // m: a rig, not a survey
  const std::size_t line = file.entries.find(key)->second.line;
  if (!(P(0, 0) > 0.0 && P(1, 1) > 0.0 && P(2, 2) > 0.0)) {
    throw ParseError(file.path, line,
                     fmt::format("expected '{}' to be a projection K[I|t] with positive focal lengths", key));
  }
  if (P(0, 1) != 0.0 || P(1, 0) != 0.0 || P(2, 0) != 0.0 || P(2, 1) != 0.0 || std::abs(P(2, 2) - 1.0) > 1e-9) {
    throw ParseError(file.path, line,
                     fmt::format("expected '{}' to be a rectified projection K[I|t]: 0 at (1,2), (2,1), (3,1), (3,2) "
                                 "and 1 at (3,3)",
                                 key));
  }
  PinholeCamera camera;
  camera.fx = P(0, 0);
  camera.fy = P(1, 1);
  camera.cx = P(0, 2);
  camera.cy = P(1, 2);
  camera.width = width;
  camera.height = height;
  if (const auto why = camera.implausibility()) {
    throw ParseError(file.path, line, fmt::format("'{}': {}", key, *why));
  }
  const Eigen::Vector3d t = P.leftCols<3>().inverse() * P.col(3);
  if (!(t.norm() <= kMaxOffset)) {
    throw ParseError(file.path, line,
                     fmt::format("'{}' puts the camera {:g} m from cam0 (expected at most {} m)", key, t.norm(),
                                 kMaxOffset));
  }
}

// R must be a rotation (to 1e-4: KITTI's printed rotations are orthonormal to ~1e-7) and t a plausible
// offset, or the calibration would move and scale every point.
void check_rigid(const KeyValueFile& file, const std::string& key, const Eigen::Matrix3d& R,
                 const Eigen::Vector3d& t = Eigen::Vector3d::Zero(), const std::string& t_key = {}) {
  constexpr double kMaxOffset = 100.0;  // m
  const std::size_t line = file.entries.find(key)->second.line;
  const std::size_t t_line = t_key.empty() ? line : file.entries.find(t_key)->second.line;
  const double error = rotation_error(R);
  if (!(error <= 1e-4)) {
    throw ParseError(file.path, line,
                     fmt::format("expected '{}' to hold a rotation matrix (orthonormal, det +1), found R^T R - I or "
                                 "det R - 1 off by {:.2g}",
                                 key, error));
  }
  if (!(t.norm() <= kMaxOffset)) {
    throw ParseError(file.path, t_line,
                     fmt::format("expected '{}' to hold a translation of at most {} m, found {:g} m",
                                 t_key.empty() ? key : t_key, kMaxOffset, t.norm()));
  }
}

}  // namespace

Matrix34d CameraCalibration::P_img_lidar() const {
  return camera.K() * T_cam_lidar.matrix().topRows<3>();
}

CameraCalibration KittiCalibration::camera(int index) const {
  if (index < 0 || index > 3) throw ConfigError("camera", "a KITTI camera index 0..3");
  const Matrix34d& Pi = P[static_cast<std::size_t>(index)];
  CameraCalibration c;
  c.camera.fx = Pi(0, 0);
  c.camera.fy = Pi(1, 1);
  c.camera.cx = Pi(0, 2);
  c.camera.cy = Pi(1, 2);
  c.camera.width = width[static_cast<std::size_t>(index)];
  c.camera.height = height[static_cast<std::size_t>(index)];
  // P_i = K [I | t_i]  =>  t_i = K^-1 * P_i.col(3): the camera's offset from rectified cam0.
  const Eigen::Matrix3d K = Pi.leftCols<3>();
  c.T_cam_cam0 = make_isometry(Eigen::Matrix3d::Identity(), K.inverse() * Pi.col(3));
  c.T_cam_lidar = c.T_cam_cam0 * T_cam0_lidar;
  return c;
}

double KittiCalibration::baseline(int a, int b) const {
  return (camera(a).T_cam_cam0.translation() - camera(b).T_cam_cam0.translation()).norm();
}

KittiCalibration read_kitti_odometry_calibration(const std::filesystem::path& calib_txt, int width,
                                                 int height) {
  std::ifstream in = open_calibration(calib_txt);
  return parse_kitti_odometry_calibration(in, calib_txt, width, height);
}

KittiCalibration parse_kitti_odometry_calibration(std::istream& in, const std::filesystem::path& source,
                                                  int width, int height) {
  const KeyValueFile file = parse_key_value(in, source);
  KittiCalibration calib;
  for (int i = 0; i < 4; ++i) {
    const std::string key = fmt::format("P{}", i);
    calib.P[static_cast<std::size_t>(i)] = row_major<3, 4>(file.get(key, 12).values);
    check_projection(file, key, calib.P[static_cast<std::size_t>(i)], width, height);
  }
  const Matrix34d Tr = row_major<3, 4>(file.get("Tr", 12).values);
  check_rigid(file, "Tr", Tr.leftCols<3>(), Tr.col(3));
  calib.T_cam0_lidar = isometry_from_3x4(Tr);
  calib.width.fill(width);
  calib.height.fill(height);
  return calib;
}

KittiCalibration read_kitti_raw_calibration(const std::filesystem::path& date_dir) {
  const auto cam_path = date_dir / "calib_cam_to_cam.txt";
  const auto velo_path = date_dir / "calib_velo_to_cam.txt";
  std::ifstream cam_in = open_calibration(cam_path);
  std::ifstream velo_in = open_calibration(velo_path);
  return parse_kitti_raw_calibration(cam_in, cam_path, velo_in, velo_path);
}

KittiCalibration parse_kitti_raw_calibration(std::istream& cam_to_cam, const std::filesystem::path& cam_source,
                                             std::istream& velo_to_cam, const std::filesystem::path& velo_source) {
  const KeyValueFile cam = parse_key_value(cam_to_cam, cam_source);
  const KeyValueFile velo = parse_key_value(velo_to_cam, velo_source);
  KittiCalibration calib;
  for (int i = 0; i < 4; ++i) {
    const auto idx = static_cast<std::size_t>(i);
    const std::string p_key = fmt::format("P_rect_0{}", i);
    calib.P[idx] = row_major<3, 4>(cam.get(p_key, 12).values);
    const std::string s_key = fmt::format("S_rect_0{}", i);
    const auto& size = cam.get(s_key, 2);
    if (!(size.values[0] >= 1.0 && size.values[0] <= 1e5 && size.values[1] >= 1.0 && size.values[1] <= 1e5)) {
      throw ParseError(cam.path, size.line, fmt::format("expected '{}' to be an image size (width height)", s_key));
    }
    calib.width[idx] = static_cast<int>(size.values[0]);
    calib.height[idx] = static_cast<int>(size.values[1]);
    check_projection(cam, p_key, calib.P[idx], calib.width[idx], calib.height[idx]);
  }
  const Eigen::Matrix3d R_rect = row_major<3, 3>(cam.get("R_rect_00", 9).values);
  check_rigid(cam, "R_rect_00", R_rect);
  const Eigen::Matrix3d R = row_major<3, 3>(velo.get("R", 9).values);
  const Eigen::Vector3d t = row_major<3, 1>(velo.get("T", 3).values);
  check_rigid(velo, "R", R, t, "T");
  calib.T_cam0_lidar = make_isometry(R_rect, Eigen::Vector3d::Zero()) * make_isometry(R, t);
  return calib;
}

}  // namespace rgbl
