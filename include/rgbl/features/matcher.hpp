#pragma once
// Descriptor matching: a per-frame grid for radius queries, a projection-guided matcher (tracking) and
// a brute-force matcher with ratio test (initialisation, relocalisation).

#include "rgbl/features/types.hpp"

#include <span>
#include <vector>

namespace rgbl {

// Buckets keypoint indices by square cells (compressed rows: one offsets array, one index array) so
// that a radius query touches only the cells overlapping its window. Keeps its own copy of the
// positions and levels, so the keypoint vector may be moved or destroyed after construction.
class FeatureGrid {
 public:
  FeatureGrid() = default;
  FeatureGrid(std::span<const Keypoint> keypoints, int width, int height, int cell_size = 16);

  // Indices of keypoints within `radius` px of (x, y) (square window: |dx| <= radius and
  // |dy| <= radius) with min_level <= level <= max_level (max_level < 0: no upper bound). Clears `out`
  // first; indices come out in ascending cell order, ascending index within a cell.
  void query(float x, float y, float radius, int min_level, int max_level, std::vector<int>& out) const;

  std::size_t size() const noexcept { return points_.size(); }
  int cell_size() const noexcept { return cell_size_; }

 private:
  struct Entry {
    float x, y;
    int level;
  };
  int cell_size_ = 16;
  int cols_ = 0, rows_ = 0;
  std::vector<Entry> points_;       // by keypoint index
  std::vector<int> cell_offsets_;   // cols_ * rows_ + 1 offsets into cell_indices_
  std::vector<int> cell_indices_;   // keypoint indices grouped by cell
};

// A predicted observation, e.g. a map point projected with the predicted pose.
struct GuidedQuery {
  float x = 0, y = 0;  // predicted pixel
  int level = 0;       // predicted pyramid level (search radius scales with its scale factor)
  float angle = 0;     // descriptor angle of the query, degrees, for the rotation histogram
  const Descriptor* descriptor = nullptr;  // null: the query is skipped (result -1)
};

struct GuidedMatchOptions {
  float radius = 15.0F;     // px at level 0, multiplied by scale^level
  float scale_factor = 1.2F;
  int level_window = 1;     // accept keypoints with |level - query.level| <= level_window
  int max_distance = 100;   // Hamming
  // Ratio test: best < ratio * second best. As in ORB-SLAM, the second best only counts when it lies
  // on the same pyramid level as the best (a near-duplicate at another scale is the same structure,
  // not an ambiguity). ratio = 1 disables the test.
  float ratio = 0.8F;
  // Rotation consistency of the matches (rotation_consistent below, with query.angle - keypoint.angle).
  bool check_orientation = true;
  int histogram_bins = 30;
  int keep_bins = 3;
  void validate() const;
};

// result[i] = index of the keypoint matched to queries[i], or -1. Each keypoint is matched at most
// once: the query with the smaller Hamming distance wins (ties: the lower query index).
std::vector<int> match_guided(std::span<const GuidedQuery> queries, const FeatureGrid& grid,
                              std::span<const Keypoint> keypoints, std::span<const Descriptor> descriptors,
                              const GuidedMatchOptions& options);

// Rotation consistency (ORB-SLAM's rule): rotations[i] is match i's angle difference in degrees (any
// sign), binned in `bins` bins of 360 / bins degrees centred on multiples of the width. A match is kept
// (1) when its bin is one of the keep_bins fullest (ties: the lower bin) and holds at least 10 % of the
// fullest bin's matches: one rigid image rotation moves every keypoint's angle alike.
std::vector<char> rotation_consistent(std::span<const float> rotations, int bins, int keep_bins);

struct BruteForceMatchOptions {
  int max_distance = 100;   // Hamming, inclusive
  float ratio = 0.7F;       // best < ratio * second best over all train descriptors; 1 disables
  bool cross_check = false; // also require the query to be the train descriptor's nearest query
  void validate() const;
};

struct Match {
  int query = -1;
  int train = -1;
  int distance = 0;
  int second_distance = 0;  // to the second-nearest train descriptor (INT_MAX: none), for own ratio tests
};

// Nearest train descriptor for every query that passes the distance, ratio (and cross) checks, in
// ascending query order. A train descriptor may be matched by several queries unless cross_check.
std::vector<Match> match_brute_force(std::span<const Descriptor> query, std::span<const Descriptor> train,
                                     const BruteForceMatchOptions& options);

}  // namespace rgbl
