#include "rgbl/features/matcher.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace rgbl {

FeatureGrid::FeatureGrid(std::span<const Keypoint> keypoints, int width, int height, int cell_size)
    : cell_size_(cell_size) {
  require(cell_size > 0, "feature_grid.cell_size", "> 0");
  require(width > 0 && height > 0, "feature_grid.size", "width and height > 0");
  cols_ = (width + cell_size - 1) / cell_size;
  rows_ = (height + cell_size - 1) / cell_size;
  points_.reserve(keypoints.size());
  std::vector<int> cell_of(keypoints.size());
  cell_offsets_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_) + 1, 0);
  const float inv = 1.0F / static_cast<float>(cell_size);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const Keypoint& k = keypoints[i];
    points_.push_back({k.x, k.y, k.level});
    // Keypoints slightly outside the image (sub-pixel positions at the border) go to the edge cells.
    const int cx = std::clamp(static_cast<int>(std::floor(k.x * inv)), 0, cols_ - 1);
    const int cy = std::clamp(static_cast<int>(std::floor(k.y * inv)), 0, rows_ - 1);
    cell_of[i] = cy * cols_ + cx;
    ++cell_offsets_[static_cast<std::size_t>(cell_of[i]) + 1];
  }
  for (std::size_t c = 1; c < cell_offsets_.size(); ++c) cell_offsets_[c] += cell_offsets_[c - 1];
  cell_indices_.resize(keypoints.size());
  std::vector<int> fill(cell_offsets_.begin(), cell_offsets_.end() - 1);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    cell_indices_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = static_cast<int>(i);
  }
}

void FeatureGrid::query(float x, float y, float radius, int min_level, int max_level, std::vector<int>& out) const {
  out.clear();
  if (points_.empty() || !(radius >= 0.0F)) return;
  const float inv = 1.0F / static_cast<float>(cell_size_);
  const int x0 = std::max(0, static_cast<int>(std::floor((x - radius) * inv)));
  const int x1 = std::min(cols_ - 1, static_cast<int>(std::floor((x + radius) * inv)));
  const int y0 = std::max(0, static_cast<int>(std::floor((y - radius) * inv)));
  const int y1 = std::min(rows_ - 1, static_cast<int>(std::floor((y + radius) * inv)));
  if (x0 > x1 || y0 > y1) return;
  const int upper = max_level < 0 ? std::numeric_limits<int>::max() : max_level;
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      const auto cell = static_cast<std::size_t>(cy * cols_ + cx);
      for (int j = cell_offsets_[cell]; j < cell_offsets_[cell + 1]; ++j) {
        const int index = cell_indices_[static_cast<std::size_t>(j)];
        const Entry& e = points_[static_cast<std::size_t>(index)];
        if (e.level < min_level || e.level > upper) continue;
        if (std::abs(e.x - x) > radius || std::abs(e.y - y) > radius) continue;
        out.push_back(index);
      }
    }
  }
}

void GuidedMatchOptions::validate() const {
  require(radius > 0.0F, "guided_match.radius", "> 0");
  require(scale_factor >= 1.0F, "guided_match.scale_factor", ">= 1");
  require(level_window >= 0, "guided_match.level_window", ">= 0");
  require(max_distance >= 0 && max_distance <= 256, "guided_match.max_distance", "in [0, 256]");
  require(ratio > 0.0F && ratio <= 1.0F, "guided_match.ratio", "in (0, 1]");
  require(histogram_bins > 0, "guided_match.histogram_bins", "> 0");
  require(keep_bins > 0 && keep_bins <= histogram_bins, "guided_match.keep_bins", "in [1, histogram_bins]");
}

void BruteForceMatchOptions::validate() const {
  require(max_distance >= 0 && max_distance <= 256, "brute_force_match.max_distance", "in [0, 256]");
  require(ratio > 0.0F && ratio <= 1.0F, "brute_force_match.ratio", "in (0, 1]");
}

namespace {

// Ratio test with ratio 1 meaning "off" (so equal best and second best still pass).
bool passes_ratio(int best, int second, float ratio) {
  if (ratio >= 1.0F || second == std::numeric_limits<int>::max()) return true;
  return static_cast<float>(best) < ratio * static_cast<float>(second);
}


// The brute-force inner loop, written once and compiled twice: as is, and (on x86-64) for the POPCNT
// instruction chosen at run time, which the default x86-64 target lacks (a software popcount is
// several times slower here).
struct BruteForceScan {
  std::span<const Descriptor> query, train;
  bool cross_check;
  std::vector<Match>& nearest;
  std::vector<int>& train_best;
  std::vector<int>& train_best_query;
};

[[gnu::always_inline]] inline int hamming_words(const Descriptor& a, const Descriptor& b) {
  int distance = 0;
  for (std::size_t i = 0; i < 32; i += 8) {
    std::uint64_t wa = 0, wb = 0;
    std::memcpy(&wa, a.data() + i, 8);
    std::memcpy(&wb, b.data() + i, 8);
    distance += __builtin_popcountll(wa ^ wb);
  }
  return distance;
}

[[gnu::always_inline]] inline void scan_all(BruteForceScan& s) {
  constexpr int kNone = std::numeric_limits<int>::max();
  for (std::size_t qi = 0; qi < s.query.size(); ++qi) {
    int best = kNone, second = kNone, best_index = -1;
    const Descriptor& q = s.query[qi];
    for (std::size_t ti = 0; ti < s.train.size(); ++ti) {
      const int d = hamming_words(q, s.train[ti]);
      if (d < best) {
        second = best;
        best = d;
        best_index = static_cast<int>(ti);
      } else if (d < second) {
        second = d;
      }
      if (s.cross_check && d < s.train_best[ti]) {
        s.train_best[ti] = d;
        s.train_best_query[ti] = static_cast<int>(qi);
      }
    }
    s.nearest[qi] = {static_cast<int>(qi), best_index, best, second};
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define RGBL_HAVE_POPCNT_PATH 1
__attribute__((target("popcnt"))) void scan_with_popcnt(BruteForceScan& s) { scan_all(s); }

bool cpu_has_popcnt() {
  static const bool has = __builtin_cpu_supports("popcnt") != 0;
  return has;
}
#endif

// Hamming distances from q to the candidates' descriptors, with the same POPCNT dispatch.
[[gnu::always_inline]] inline void candidate_distances_impl(const Descriptor& q, std::span<const Descriptor> descriptors,
                                                            const std::vector<int>& candidates, std::vector<int>& out) {
  out.resize(candidates.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    out[i] = hamming_words(q, descriptors[static_cast<std::size_t>(candidates[i])]);
  }
}

#if defined(RGBL_HAVE_POPCNT_PATH)
__attribute__((target("popcnt"))) void candidate_distances_popcnt(const Descriptor& q,
                                                                  std::span<const Descriptor> descriptors,
                                                                  const std::vector<int>& candidates,
                                                                  std::vector<int>& out) {
  candidate_distances_impl(q, descriptors, candidates, out);
}
#endif

void candidate_distances(const Descriptor& q, std::span<const Descriptor> descriptors, const std::vector<int>& candidates,
                         std::vector<int>& out) {
#if defined(RGBL_HAVE_POPCNT_PATH)
  if (cpu_has_popcnt()) {
    candidate_distances_popcnt(q, descriptors, candidates, out);
    return;
  }
#endif
  candidate_distances_impl(q, descriptors, candidates, out);
}

}  // namespace

std::vector<int> match_guided(std::span<const GuidedQuery> queries, const FeatureGrid& grid,
                              std::span<const Keypoint> keypoints, std::span<const Descriptor> descriptors,
                              const GuidedMatchOptions& options) {
  options.validate();
  require(keypoints.size() == descriptors.size() && grid.size() == keypoints.size(), "match_guided.inputs",
          "grid, keypoints and descriptors of the same frame");
  constexpr int kNone = std::numeric_limits<int>::max();
  std::vector<int> result(queries.size(), -1);
  std::vector<int> distance_of_query(queries.size(), kNone);
  // Which query currently owns each keypoint (-1: none); a better query takes it over.
  std::vector<int> owner(keypoints.size(), -1);
  std::vector<int> candidates, distances;

  for (std::size_t qi = 0; qi < queries.size(); ++qi) {
    const GuidedQuery& q = queries[qi];
    if (q.descriptor == nullptr) continue;
    const float r = options.radius * std::pow(options.scale_factor, static_cast<float>(std::max(q.level, 0)));
    grid.query(q.x, q.y, r, q.level - options.level_window, q.level + options.level_window, candidates);
    int best = kNone, second = kNone, best_index = -1, best_level = -1, second_level = -1;
    candidate_distances(*q.descriptor, descriptors, candidates, distances);
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const int index = candidates[c];
      const int d = distances[c];
      const int level = keypoints[static_cast<std::size_t>(index)].level;
      if (d < best) {
        second = best;
        second_level = best_level;
        best = d;
        best_index = index;
        best_level = level;
      } else if (d < second) {
        second = d;
        second_level = level;
      }
    }
    if (best_index < 0 || best > options.max_distance) continue;
    if (second_level == best_level && !passes_ratio(best, second, options.ratio)) continue;
    int& current = owner[static_cast<std::size_t>(best_index)];
    if (current >= 0) {
      if (distance_of_query[static_cast<std::size_t>(current)] <= best) continue;  // earlier query is as good
      result[static_cast<std::size_t>(current)] = -1;
      distance_of_query[static_cast<std::size_t>(current)] = kNone;
    }
    current = static_cast<int>(qi);
    result[qi] = best_index;
    distance_of_query[qi] = best;
  }

  if (options.check_orientation) {
    std::vector<std::size_t> matched;
    std::vector<float> rotations;
    for (std::size_t qi = 0; qi < queries.size(); ++qi) {
      if (result[qi] < 0) continue;
      matched.push_back(qi);
      rotations.push_back(queries[qi].angle - keypoints[static_cast<std::size_t>(result[qi])].angle);
    }
    const std::vector<char> keep = rotation_consistent(rotations, options.histogram_bins, options.keep_bins);
    for (std::size_t i = 0; i < matched.size(); ++i) {
      if (keep[i] == 0) result[matched[i]] = -1;
    }
  }
  return result;
}

std::vector<char> rotation_consistent(std::span<const float> rotations, int bins, int keep_bins) {
  require(bins > 0, "rotation_consistent.bins", "> 0");
  require(keep_bins > 0 && keep_bins <= bins, "rotation_consistent.keep_bins", "in [1, bins]");
  const float bin_width = 360.0F / static_cast<float>(bins);
  std::vector<int> bin_of(rotations.size());
  std::vector<int> counts(static_cast<std::size_t>(bins), 0);
  for (std::size_t i = 0; i < rotations.size(); ++i) {
    float rot = std::fmod(rotations[i], 360.0F);
    if (rot < 0.0F) rot += 360.0F;
    int bin = static_cast<int>(std::lround(rot / bin_width));
    if (bin >= bins) bin -= bins;
    bin_of[i] = bin;
    ++counts[static_cast<std::size_t>(bin)];
  }
  // The keep_bins fullest bins (ties: lower bin), each kept only with >= 10% of the fullest count.
  std::vector<int> order(static_cast<std::size_t>(bins));
  for (int b = 0; b < bins; ++b) order[static_cast<std::size_t>(b)] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return counts[static_cast<std::size_t>(a)] > counts[static_cast<std::size_t>(b)];
  });
  std::vector<char> keep_bin(static_cast<std::size_t>(bins), 0);
  const int top = counts[static_cast<std::size_t>(order[0])];
  for (int k = 0; k < keep_bins; ++k) {
    const int b = order[static_cast<std::size_t>(k)];
    const int c = counts[static_cast<std::size_t>(b)];
    if (c > 0 && 10 * c >= top) keep_bin[static_cast<std::size_t>(b)] = 1;
  }
  std::vector<char> keep(rotations.size());
  for (std::size_t i = 0; i < rotations.size(); ++i) keep[i] = keep_bin[static_cast<std::size_t>(bin_of[i])];
  return keep;
}

std::vector<Match> match_brute_force(std::span<const Descriptor> query, std::span<const Descriptor> train,
                                     const BruteForceMatchOptions& options) {
  options.validate();
  constexpr int kNone = std::numeric_limits<int>::max();
  std::vector<Match> matches;
  if (query.empty() || train.empty()) return matches;
  // Nearest query of every train descriptor, only needed for the cross check.
  std::vector<int> train_best(options.cross_check ? train.size() : 0, kNone);
  std::vector<int> train_best_query(train_best.size(), -1);
  std::vector<Match> nearest(query.size());
  BruteForceScan scan{query, train, options.cross_check, nearest, train_best, train_best_query};
#if defined(RGBL_HAVE_POPCNT_PATH)
  if (cpu_has_popcnt()) {
    scan_with_popcnt(scan);
  } else
#endif
  {
    scan_all(scan);
  }
  for (std::size_t qi = 0; qi < query.size(); ++qi) {
    const Match& m = nearest[qi];
    if (m.distance > options.max_distance || !passes_ratio(m.distance, m.second_distance, options.ratio)) continue;
    if (options.cross_check && train_best_query[static_cast<std::size_t>(m.train)] != m.query) continue;
    matches.push_back(m);
  }
  return matches;
}

}  // namespace rgbl
