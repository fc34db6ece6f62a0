#pragma once
// A LiDAR place descriptor in the manner of Scan Context (Kim and Kim, IROS 2018): the scan, seen from
// above, cut into rings (range) and sectors (azimuth); each cell holds the height of its highest point.
// A change of heading only rotates the sectors, so two scans of one place compare by the best circular
// shift of their columns, and that shift is the heading change. Needs no training. Loop-closing
// candidates come from here (docs/loop-closing.md).

#include "rgbl/geometry/point_cloud.hpp"

#include <cstddef>
#include <functional>
#include <vector>

namespace rgbl {

struct ScanContextOptions {
  int rings = 20;             // at most 1000
  int sectors = 60;           // 6 degrees each; at most 3600
  double max_range = 80.0;    // m, horizontal; farther points are dropped
  double min_range = 2.0;     // m; nearer points are the ego car
  // Added to z so that every cell of a scan from a sensor ~1.7 m above the road is positive: an empty
  // cell (0) then differs from a cell holding only road.
  double height_offset = 2.0;  // m

  void validate() const;
};

class ScanContext {
 public:
  ScanContext() = default;
  ScanContext(int rings, int sectors);

  int rings() const { return rings_; }
  int sectors() const { return sectors_; }
  bool empty() const { return rings_ == 0; }
  // z + height_offset of the highest point in the cell, clamped at 0; 0 = no point.
  float cell(int ring, int sector) const { return cells_[static_cast<std::size_t>(ring * sectors_ + sector)]; }
  float& cell(int ring, int sector) { return cells_[static_cast<std::size_t>(ring * sectors_ + sector)]; }
  // Per ring, the fraction of its sectors holding a point: unchanged by a rotation, so it finds
  // candidates before the shift search.
  const std::vector<float>& ring_key() const { return ring_key_; }
  void update_ring_key();

 private:
  int rings_ = 0, sectors_ = 0;
  std::vector<float> cells_;  // ring-major
  std::vector<float> ring_key_;
};

// Sector s covers azimuth [-pi + s * 2pi / sectors, -pi + (s + 1) * 2pi / sectors), azimuth = atan2(y, x)
// in the LiDAR frame (x ahead, y left, z up), so sectors grow counter-clockwise and straight behind
// (azimuth +-pi) is sector 0; ring r covers horizontal range
// [min_range + r * step, min_range + (r + 1) * step), step = (max_range - min_range) / rings.
// Non-finite points are skipped.
ScanContext make_scan_context(PointCloudView scan, const ScanContextOptions& options = {});

struct ScanContextMatch {
  double distance = 1.0;  // mean over columns occupied in both of (1 - cosine similarity); 0 = same place
  int sector_shift = 0;   // query sector s corresponds to candidate sector (s + sector_shift) mod sectors
  // Heading of the query relative to the candidate, counter-clockwise positive, in (-pi, pi]: a point at
  // azimuth a in the query's LiDAR frame lies at a + yaw in the candidate's. Resolution: one sector.
  double yaw = 0.0;
};

// Best circular shift, coarse to fine: the sector keys (each column's mean) are aligned at every shift
// (sectors^2 adds), and the full comparison runs only within 2 sectors of the 3 best key alignments and
// of every alignment tied with the best (15 of 60 shifts at the defaults, unless keys tie). The result
// is that of compare_all_shifts whenever its shift is among those, which always holds for a
// whole-sector rotation of one scan (its key alignment is exact). Throws ConfigError when the two
// descriptors differ in size. No common occupied column at any shift searched: distance 1.
ScanContextMatch compare(const ScanContext& query, const ScanContext& candidate);

// The same comparison at every shift (rings x sectors^2 multiply-adds: ~72k at the defaults): the
// reference for compare(), and the choice when its ~3x the time does not matter.
ScanContextMatch compare_all_shifts(const ScanContext& query, const ScanContext& candidate);

// Places seen so far: ring-key nearest neighbours (brute force: keyframes number thousands, not
// millions), then the shift search on those.
class ScanContextDatabase {
 public:
  struct Candidate {
    std::size_t id = 0;
    ScanContextMatch match;
  };

  void add(std::size_t id, ScanContext context);
  std::size_t size() const { return entries_.size(); }
  // The `ring_key_neighbours` entries nearest by ring key among those `allowed` accepts (e.g. not
  // covisible with the query's keyframe), compared in full; sorted by distance, best first.
  std::vector<Candidate> query(const ScanContext& context, std::size_t ring_key_neighbours,
                               const std::function<bool(std::size_t)>& allowed = {}) const;

 private:
  struct Entry {
    std::size_t id;
    ScanContext context;
  };
  std::vector<Entry> entries_;
};

}  // namespace rgbl
