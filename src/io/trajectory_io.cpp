#include "rgbl/io/trajectory_io.hpp"

#include "rgbl/core/error.hpp"
#include "text.hpp"

#include "rgbl/core/file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace rgbl {
namespace {

// Rotations read from files are checked loosely (6-digit files are orthonormal to ~1e-6 only).
bool is_rotation(const Eigen::Matrix3d& R) {
  return (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3 &&
         std::abs(R.determinant() - 1.0) < 1e-3;
}

}  // namespace

void write_kitti_trajectory(const std::filesystem::path& file, std::span<const Eigen::Isometry3d> poses) {
  write_atomically(file, [&](std::ofstream& out) {
    std::string line;
    for (const auto& T : poses) {
      line.clear();
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) {
          if (r != 0 || c != 0) line += ' ';
          line += fmt::format("{}", T.matrix()(r, c));
        }
      }
      line += '\n';
      out << line;
    }
  });
}

std::vector<Eigen::Isometry3d> read_kitti_trajectory(const std::filesystem::path& file) {
  auto in = detail::open_for_reading(file, "a KITTI trajectory: 12 numbers per line");
  return read_kitti_trajectory(in, file);
}

std::vector<Eigen::Isometry3d> read_kitti_trajectory(std::istream& in, const std::filesystem::path& file) {
  std::vector<Eigen::Isometry3d> poses;
  detail::for_each_record(in, file, 12, "12 numbers (a row-major 3x4 pose)",
                          [&](std::size_t line_no, std::span<const double> v) {
                            Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
                            for (int k = 0; k < 12; ++k) T.matrix()(k / 4, k % 4) = v[static_cast<std::size_t>(k)];
                            if (!is_rotation(T.linear())) {
                              throw ParseError(file, line_no, "the left 3x3 block is not a rotation matrix");
                            }
                            poses.push_back(T);
                          });
  return poses;
}

void write_tum_trajectory(const std::filesystem::path& file, const Trajectory& trajectory) {
  if (trajectory.timestamps.size() != trajectory.poses.size()) {
    throw Error(fmt::format("{}: {} timestamps for {} poses", file.string(), trajectory.timestamps.size(),
                            trajectory.poses.size()));
  }
  write_atomically(file, [&](std::ofstream& out) {
    out << "# timestamp tx ty tz qx qy qz qw\n";
    for (std::size_t i = 0; i < trajectory.size(); ++i) {
      const auto& T = trajectory.poses[i];
      const Eigen::Quaterniond q(T.linear());
      const Eigen::Vector3d t = T.translation();
      out << fmt::format("{} {} {} {} {} {} {} {}\n", trajectory.timestamps[i], t.x(), t.y(), t.z(), q.x(), q.y(),
                         q.z(), q.w());
    }
  });
}

Trajectory read_tum_trajectory(const std::filesystem::path& file) {
  auto in = detail::open_for_reading(file, "a TUM trajectory: 't tx ty tz qx qy qz qw' per line");
  return read_tum_trajectory(in, file);
}

Trajectory read_tum_trajectory(std::istream& in, const std::filesystem::path& file) {
  Trajectory trajectory;
  detail::for_each_record(
      in, file, 8, "8 numbers 't tx ty tz qx qy qz qw'",
      [&](std::size_t line_no, std::span<const double> v) {
        Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
        if (std::abs(q.norm() - 1.0) > 1e-3) {
          throw ParseError(file, line_no, fmt::format("quaternion norm is {}, expected 1", q.norm()));
        }
        if (!trajectory.timestamps.empty() && v[0] <= trajectory.timestamps.back()) {
          throw ParseError(file, line_no, "timestamps must increase");
        }
        q.normalize();
        Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
        T.linear() = q.toRotationMatrix();
        T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
        trajectory.timestamps.push_back(v[0]);
        trajectory.poses.push_back(T);
      });
  return trajectory;
}

std::vector<std::pair<std::size_t, std::size_t>> associate_timestamps(std::span<const double> a,
                                                                      std::span<const double> b,
                                                                      double max_difference) {
  // Greedy by smallest difference over all candidate pairs, as TUM's associate.py does.
  struct Candidate {
    double difference;
    std::size_t i, j;
  };
  std::vector<Candidate> candidates;
  std::size_t lo = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    while (lo < b.size() && b[lo] < a[i] - max_difference) ++lo;
    for (std::size_t j = lo; j < b.size() && b[j] <= a[i] + max_difference; ++j) {
      candidates.push_back({std::abs(a[i] - b[j]), i, j});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.difference < y.difference; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (const auto& c : candidates) {
    if (used_a[c.i] || used_b[c.j]) continue;
    used_a[c.i] = used_b[c.j] = true;
    pairs.emplace_back(c.i, c.j);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace rgbl
