#include "rgbl/geometry/scan_agreement.hpp"

#include "rgbl/core/disjoint_sets.hpp"
#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rgbl {

void ScanSampleOptions::validate() const {
  require(stride >= 1, "scan_sample.stride", ">= 1");
  require(std::isfinite(min_range) && min_range >= 0.0, "scan_sample.min_range", ">= 0 m");
  require(std::isfinite(max_range) && max_range > min_range, "scan_sample.max_range", "finite and > min_range");
  require(std::isfinite(tolerance) && tolerance > 0.0, "scan_sample.tolerance", "> 0 m");
  require(std::isfinite(elevation_correction_deg) && std::abs(elevation_correction_deg) <= 2.0,
          "scan_sample.elevation_correction_deg", "an angle in [-2, 2] deg");
}

ScanSample sample_scan(PointCloudView scan, const Eigen::Isometry3d& T_cam_lidar, const ScanSampleOptions& options) {
  ScanSample sample;
  const auto min2 = static_cast<float>(options.min_range * options.min_range);
  const auto max2 = static_cast<float>(options.max_range * options.max_range);
  const Eigen::Isometry3f T = T_cam_lidar.cast<float>();
  sample.points.reserve(scan.size() / options.stride + 1);
  // turning up by a about p x z rotates (horizontal distance h, height z) by a in its own vertical plane
  const double a = options.elevation_correction_deg * std::numbers::pi / 180.0;
  const auto ca = static_cast<float>(std::cos(a)), sa = static_cast<float>(std::sin(a));
  for (std::size_t i = 0; i < scan.size(); i += options.stride) {
    Eigen::Vector3f p(scan[i].x, scan[i].y, scan[i].z);
    const float r2 = p.squaredNorm();
    if (!(r2 >= min2 && r2 <= max2)) continue;  // also drops NaN
    if (a != 0.0) {
      const float h = std::hypot(p.x(), p.y());
      if (h > 0.0F) {
        const float h_turned = h * ca - p.z() * sa, scale = h_turned / h;
        p = Eigen::Vector3f(p.x() * scale, p.y() * scale, h * sa + p.z() * ca);
      }
    }
    sample.points.push_back(T * p);
  }
  return sample;
}

std::vector<LidarPoint> as_points(const ScanSample& sample) {
  std::vector<LidarPoint> points(sample.points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i].x = sample.points[i].x();
    points[i].y = sample.points[i].y();
    points[i].z = sample.points[i].z();
  }
  return points;
}

ScanAgreement::ScanAgreement(const ScanSample& reference, double tolerance)
    : tolerance_(static_cast<float>(tolerance)),
      // Voxels of twice the tolerance: every point within the tolerance of a query lies in the 2x2x2
      // block around it.
      reference_(reference.points, 0.5F / tolerance_) {}

bool ScanAgreement::lands(const Eigen::Vector3f& p) const {
  // a pose gone wild puts points anywhere: beyond 100 km (or not finite) nothing lands, and the voxel
  // coordinates below stay within int32
  constexpr float kFar = 1e5F;
  if (!(p.cwiseAbs().maxCoeff() < kFar)) return false;
  // the block's lowest voxel: p - tolerance lies in it on every axis, p + tolerance in the one above
  const VoxelKey low = voxel_of(Eigen::Vector3f(p.array() - tolerance_), 0.5F / tolerance_);
  const float tolerance2 = tolerance_ * tolerance_;
  for (int dx = 0; dx <= 1; ++dx) {
    for (int dy = 0; dy <= 1; ++dy) {
      for (int dz = 0; dz <= 1; ++dz) {
        const std::uint32_t slot = reference_.index.find({low.x + dx, low.y + dy, low.z + dz});
        if (slot == VoxelIndex::npos) continue;
        for (std::uint32_t j = reference_.begin[slot]; j < reference_.begin[slot + 1]; ++j) {
          if ((reference_.points[j] - p).squaredNorm() <= tolerance2) return true;
        }
      }
    }
  }
  return false;
}

std::size_t ScanAgreement::count(const ScanSample& query, const Eigen::Isometry3d& T_reference_query) const {
  const Eigen::Isometry3f T = T_reference_query.cast<float>();
  std::size_t agreeing = 0;
  for (const Eigen::Vector3f& q : query.points) agreeing += lands(T * q) ? 1 : 0;
  return agreeing;
}

std::vector<bool> ScanAgreement::agreeing(const ScanSample& query, const Eigen::Isometry3d& T_reference_query) const {
  const Eigen::Isometry3f T = T_reference_query.cast<float>();
  std::vector<bool> flags(query.points.size());
  for (std::size_t i = 0; i < query.points.size(); ++i) flags[i] = lands(T * query.points[i]);
  return flags;
}

double signed_rank_z(std::span<const double> differences) {
  std::vector<double> d;
  for (const double x : differences) {
    if (x != 0.0) d.push_back(x);  // zeros carry no sign (Wilcoxon's convention: dropped)
  }
  const auto n = static_cast<double>(d.size());
  if (d.empty()) return 0.0;
  std::sort(d.begin(), d.end(), [](double x, double y) { return std::abs(x) < std::abs(y); });
  double w_plus = 0.0, ties = 0.0;
  for (std::size_t i = 0; i < d.size();) {
    std::size_t j = i;
    while (j < d.size() && std::abs(d[j]) == std::abs(d[i])) ++j;
    const double rank = 0.5 * static_cast<double>(i + 1 + j);  // ranks i+1..j averaged
    for (std::size_t k = i; k < j; ++k) w_plus += d[k] > 0.0 ? rank : 0.0;
    const auto t = static_cast<double>(j - i);
    ties += t * t * t - t;
    i = j;
  }
  const double mean = n * (n + 1.0) / 4.0;
  const double variance = n * (n + 1.0) * (2.0 * n + 1.0) / 24.0 - ties / 48.0;
  return variance > 0.0 ? (w_plus - mean) / std::sqrt(variance) : 0.0;
}

std::vector<std::uint32_t> label_objects(const ScanSample& sample, double edge) {
  require(std::isfinite(edge) && edge > 0.0, "label_objects: edge", "> 0 m");
  const auto inv = static_cast<float>(1.0 / edge);
  VoxelIndex index;
  index.reserve(sample.points.size());
  std::vector<VoxelKey> keys;  // slot -> voxel
  std::vector<std::uint32_t> slot_of(sample.points.size());
  for (std::size_t i = 0; i < sample.points.size(); ++i) {
    const VoxelKey key = voxel_of(sample.points[i], inv);
    const auto [slot, added] = index.emplace(key, static_cast<std::uint32_t>(keys.size()));
    if (added) keys.push_back(key);
    slot_of[i] = slot;
  }
  // the voxels, each joined with its 26 neighbours
  DisjointSets groups(keys.size());
  for (std::uint32_t s = 0; s < keys.size(); ++s) {
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const std::uint32_t t = index.find({keys[s].x + dx, keys[s].y + dy, keys[s].z + dz});
          if (t == VoxelIndex::npos || t <= s) continue;  // each pair once
          groups.join(s, t);
        }
      }
    }
  }
  // labels in order of the points' first appearance
  std::vector<std::uint32_t> label_of_root(keys.size(), VoxelIndex::npos);
  std::vector<std::uint32_t> labels(sample.points.size());
  std::uint32_t next = 0;
  for (std::size_t i = 0; i < sample.points.size(); ++i) {
    std::uint32_t& label = label_of_root[groups.root(slot_of[i])];
    if (label == VoxelIndex::npos) label = next++;
    labels[i] = label;
  }
  return labels;
}

ScanVote ScanAgreement::vote(const ScanSample& query, const Eigen::Isometry3d& T_reference_query_a,
                             const Eigen::Isometry3d& T_reference_query_b,
                             std::span<const std::uint32_t> objects) const {
  require(objects.empty() || objects.size() == query.points.size(), "ScanAgreement::vote: objects",
          "one label per point of the query");
  const std::vector<bool> a = agreeing(query, T_reference_query_a);
  const std::vector<bool> b = agreeing(query, T_reference_query_b);
  ScanVote vote;
  std::vector<double> per_object;  // object -> its only_b - only_a
  if (!objects.empty()) per_object.assign(*std::max_element(objects.begin(), objects.end()) + std::size_t{1}, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool for_a = a[i] && !b[i], for_b = b[i] && !a[i];
    vote.only_a += for_a ? 1 : 0;
    vote.only_b += for_b ? 1 : 0;
    if (!objects.empty()) per_object[objects[i]] += (for_b ? 1.0 : 0.0) - (for_a ? 1.0 : 0.0);
  }
  if (!objects.empty()) vote.object_z = signed_rank_z(per_object);
  return vote;
}

int ScanVote::object_preference() const {
  if (std::isnan(object_z)) return preference();
  if (object_z > 3.0) return 1;
  if (object_z < -3.0) return -1;
  return 0;
}

int count_preference(std::size_t a, std::size_t b, double sigmas) {
  const double difference = static_cast<double>(b) - static_cast<double>(a);
  const double spread = sigmas * std::sqrt(static_cast<double>(a + b));
  if (difference > spread) return 1;
  if (-difference > spread) return -1;
  return 0;
}

int ScanVote::preference() const { return count_preference(only_a, only_b, 3.0); }

}  // namespace rgbl
