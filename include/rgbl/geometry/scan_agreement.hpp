#pragma once
// How well two LiDAR scans agree under a relative pose: the share of one scan's returns that land on
// the other's. A pose decided from images can be wrong in ways images cannot tell (a car ahead at the
// ego speed, road paint that repeats at the step length, motion blur that looks alike at zero
// motion); the scans see the static world's shape whatever the images show, and a wrong pose moves
// poles, trunks, kerbs and facades off each other.

#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/voxel_index.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace rgbl {

struct ScanSampleOptions {
  std::size_t stride = 8;    // every stride-th return (a KITTI scan: ~15k of ~120k)
  double min_range = 2.0;    // m: nearer returns are the car itself
  double max_range = 40.0;   // m: farther ones are too sparse to land on each other
  double tolerance = 0.3;    // m: a return agrees when a return of the other scan lies this close
  // Turns every return up by this angle about p x z in the LiDAR frame, its range kept: the correction
  // of a LiDAR whose beams fire higher than its points say (KITTI's HDL-64: 0.205 deg, as CT-ICP and
  // kiss-icp apply it). The sample only (scan agreement, road planes, the keyframes' scan pairs), not
  // the depth. 0 = the points as recorded.
  double elevation_correction_deg = 0.0;

  void validate() const;
};

// A subsample of a scan, in a camera frame (what a tracked frame keeps of its scan).
struct ScanSample {
  std::vector<Eigen::Vector3f> points;
  bool empty() const { return points.empty(); }
};

ScanSample sample_scan(PointCloudView scan, const Eigen::Isometry3d& T_cam_lidar, const ScanSampleOptions& options);

// The sample's points as LiDAR returns (intensity 0), e.g. to register two samples (register_scans).
std::vector<LidarPoint> as_points(const ScanSample& sample);

// The objects of a sample: points whose voxels (of edge `edge`) touch, even at a corner, share a label
// (labels 0..n-1 in order of first appearance). What is one object to the scan is one surface to a
// pose: a truck's face, a facade, a pole; its returns land or miss together.
std::vector<std::uint32_t> label_objects(const ScanSample& sample, double edge);

// Wilcoxon's signed-rank statistic of paired differences as a z-score (normal approximation, tied
// magnitudes given their average rank, zeros dropped): > 0 when the positive ones rank higher. 0
// without a nonzero difference.
double signed_rank_z(std::span<const double> differences);

// Two counts compared beyond chance: +1 for b, -1 for a, 0 when |b - a| <= sigmas sqrt(a + b) (each
// count Poisson, or McNemar's test on the discordant pairs of paired counts).
int count_preference(std::size_t a, std::size_t b, double sigmas);

// How the points of one sample vote between two poses of it against a reference: the points that
// land on the reference under one pose and not under the other.
struct ScanVote {
  std::size_t only_a = 0, only_b = 0;
  // With objects: Wilcoxon's signed-rank statistic over the objects' differences (their only_b -
  // only_a), as a z-score (normal approximation, ties averaged); NaN when counted without objects.
  double object_z = std::numeric_limits<double>::quiet_NaN();
  // +1 for b, -1 for a, 0 when the discordant points do not favour one beyond chance:
  // |only_b - only_a| <= 3 sqrt(only_a + only_b) (McNemar's test for paired counts, at 3 sigma).
  int preference() const;
  // The same with objects, not returns, as the independent units: |object_z| > 3. Two trucks' 139
  // returns for their own motion are two pieces of evidence, not 139; the ranks still let a large
  // object weigh more than a small one. Without objects, preference().
  int object_preference() const;
};

// A reference sample indexed for "is a point within the tolerance" queries (voxels of twice that edge).
class ScanAgreement {
 public:
  ScanAgreement(const ScanSample& reference, double tolerance);

  // The points of `query` (in its own frame) that land within the tolerance of a reference point
  // when moved into the reference's frame by T_reference_query.
  std::size_t count(const ScanSample& query, const Eigen::Isometry3d& T_reference_query) const;
  // The same per point of `query`: whether it agrees.
  std::vector<bool> agreeing(const ScanSample& query, const Eigen::Isometry3d& T_reference_query) const;
  // The points of `query` for pose a against pose b (both T_reference_query).
  // With `objects` (label_objects(query, ...)), the vote's object_z too.
  ScanVote vote(const ScanSample& query, const Eigen::Isometry3d& T_reference_query_a,
                const Eigen::Isometry3d& T_reference_query_b, std::span<const std::uint32_t> objects = {}) const;

 private:
  // Whether p (in the reference's frame) lies within the tolerance of a reference point.
  bool lands(const Eigen::Vector3f& p) const;

  float tolerance_;
  VoxelBuckets reference_;  // the reference, grouped by voxels of twice the tolerance
};

}  // namespace rgbl
