#pragma once
// ORB extraction (ORB-SLAM semantics): image pyramid with a geometric per-level budget, FAST with a
// per-cell threshold fallback, quadtree distribution keeping the strongest corner per node,
// intensity-centroid orientation and 256-bit rotated BRIEF on a Gaussian-smoothed level.

#include "rgbl/features/types.hpp"

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include <cstdint>

#include <span>
#include <vector>

namespace rgbl {

class TaskPool;

namespace detail {
// A FAST corner in level pixels; score = largest threshold at which it is a corner.
struct FastCorner {
  int x, y;
  int score;
};
}  // namespace detail

struct OrbOptions {
  int num_features = 2000;      // total over all levels
  int num_levels = 8;
  float scale_factor = 1.2F;    // between consecutive levels
  int fast_threshold = 12;      // per-cell threshold...
  int fast_min_threshold = 7;   // ...and the fallback for cells with no corner at fast_threshold
  int cell_size = 35;           // px at each level, for the threshold fallback
  // The quadtree splits until it has num_features / features_per_node nodes per level budget and
  // keeps the features_per_node strongest corners of each: 1 is ORB-SLAM's distribution; larger
  // values trade spread for strength (see docs/features.md).
  int features_per_node = 1;
  // Share of each level's budget placed by the quadtree; the rest goes to the strongest remaining
  // corners anywhere (1 = all spread, ORB-SLAM). Half and half matches more of the true motion than
  // either extreme on KITTI (docs/features.md); the tracker's motion prior keeps the strong corners
  // of an object moving with the camera from taking over the pose (docs/tracking.md).
  double spread_fraction = 0.5;
  int edge_threshold = 19;      // keypoints keep this many px from every level border
  int patch_size = 31;          // BRIEF patch diameter; sampling points lie within patch_size / 2
  int orientation_radius = 15;  // intensity-centroid disc radius
  int blur_size = 7;            // Gaussian kernel (odd) and sigma of the level smoothed for BRIEF
  double blur_sigma = 2.0;
  void validate() const;
};

// One pair of BRIEF sampling points, offsets from the keypoint in level pixels.
struct BriefPair {
  float x1, y1, x2, y2;
};

// `count` candidate sampling pairs from a fixed-seed generator (SplitMix64 + Box-Muller): isotropic
// Gaussian with sigma = patch_size / 5, clipped to the disc of radius patch_size / 2, points of a
// pair >= 2 px apart. The same arguments give the same pairs on every platform; a longer pool starts
// with the shorter one.
std::vector<BriefPair> make_brief_candidates(int patch_size, int count);

// The 256 pairs the extractor uses. For patch_size 31: 256 of the first 4096 candidates, chosen
// offline by apps/learn_brief_pattern (tests with a mean near 0.5 and low mutual correlation on
// real patches, the ORB paper's criterion); for other sizes the first 256 candidates.
std::vector<BriefPair> make_brief_pattern(int patch_size);

// Where a pyramid level's pixel lies in level 0. cv::resize aligns pixel centres and each level's size
// is rounded, so level x maps to (x + 0.5) * W0 / Wl - 0.5 (y likewise with the heights), not to
// x * scale_factor^l, which is off by up to 1.6 px, mostly up and left, by an amount that changes as
// a point moves through the levels (docs/features.md, "Keypoint coordinates across levels").
struct LevelMap {
  float ax = 1.0F, bx = 0.0F, ay = 1.0F, by = 0.0F;  // level 0 = a * level + b, per axis

  // level 0's size and the level's (as cv::resize made it)
  static LevelMap between(cv::Size level0, cv::Size level) noexcept;
  float image_x(float x) const noexcept { return ax * x + bx; }
  float image_y(float y) const noexcept { return ay * y + by; }
  float level_x(float x0) const noexcept { return (x0 - bx) / ax; }
  float level_y(float y0) const noexcept { return (y0 - by) / ay; }
};

// Owns the pyramid and scratch buffers, so reusing one extractor across frames allocates nothing in
// steady state. Not thread-safe: one extractor per thread. Move-only, because copies of its cv::Mat
// scratch would share pixel buffers (and race when used from two threads).
class OrbExtractor {
 public:
  explicit OrbExtractor(const OrbOptions& options = {});
  OrbExtractor(const OrbExtractor&) = delete;
  OrbExtractor& operator=(const OrbExtractor&) = delete;
  OrbExtractor(OrbExtractor&&) noexcept = default;
  OrbExtractor& operator=(OrbExtractor&&) noexcept = default;
  ~OrbExtractor() = default;

  // `gray`: CV_8UC1. Clears and fills `keypoints` (level-0 pixel coordinates) and `descriptors` (same
  // length and order). Ordered by level, then by position within the level's quadtree. Deterministic:
  // with a pool, detection and description run level by level on its threads and give the same
  // keypoints and descriptors, bit for bit, as without.
  void extract(const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors,
               TaskPool* pool = nullptr);

  const OrbOptions& options() const noexcept { return options_; }
  // scale_factor^level for every level: the nominal scale (keypoint size, search radii, sigmas).
  std::span<const float> level_scales() const noexcept { return scales_; }
  // Each level's pixels in level 0's, for the pyramid of the last extract() call.
  std::span<const LevelMap> level_maps() const noexcept { return level_maps_; }
  // Features each level aims for (the geometric series; a level's shortfall moves to the next).
  std::span<const int> level_budgets() const noexcept { return budgets_; }
  // The pyramid of the last extract() call (level 0 shares the input's data).
  std::span<const cv::Mat> pyramid() const noexcept { return pyramid_; }

 private:
  struct Candidate {
    float x, y;  // level pixels
    float response;  // the FAST score: a whole number in [0, 255]
  };
  struct Node {
    float x0, y0, x1, y1;
    int begin, end;  // range in candidates_
  };
  // What one level's detection and description use and produce: levels run independently.
  struct Level {
    std::vector<detail::FastCorner> fast;
    std::vector<std::uint8_t> fast_scores;
    std::vector<unsigned char> cell_strong;
    std::vector<int> cell_col, cell_row;  // cell column of each x and cell row (times columns) of each y
    std::vector<Candidate> candidates;
    std::vector<Candidate> selected;
    // the quadtree's scratch
    std::vector<int> root_counts;
    std::vector<Candidate> bucketed;
    std::vector<Candidate> leftover;  // corners the quadtree did not take
    std::vector<Node> nodes, next_nodes;
    cv::Mat blurred;
    std::vector<std::uint8_t> smooth_row;  // the smoothing's scratch
    std::vector<std::uint16_t> smooth_rows;
    std::vector<int> pattern_offsets;
    std::vector<Keypoint> keypoints;
    std::vector<Descriptor> descriptors;
  };
  void build_pyramid(const cv::Mat& gray);
  void detect_level(int level);
  // Keeps `target` of the level's candidates (all of them when fewer: the rest of the budget then
  // moves to the next level, which is why levels are distributed in order unless none falls short).
  void distribute(int target, Level& level);
  void describe_level(int level);

  OrbOptions options_;
  std::vector<float> scales_;
  std::vector<LevelMap> level_maps_;
  std::vector<int> budgets_;
  // The BRIEF pairs as four coordinate arrays (x1..., y1..., x2..., y2...), for rotating several at a time.
  std::vector<float> pattern_soa_;
  std::vector<int> disc_half_width_;  // per row offset 0..radius: half width of the orientation disc
  std::vector<std::uint8_t> disc_masks_;  // the same disc as 32-byte row masks for the SIMD path
  // Scratch reused across calls.
  std::vector<cv::Mat> pyramid_;
  std::vector<Level> levels_;
};

}  // namespace rgbl
