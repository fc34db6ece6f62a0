#include "rgbl/features/orb.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/task_pool.hpp"

#include "brief.hpp"
#include "fast.hpp"
#include "smooth.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rgbl {

void OrbOptions::validate() const {
  require(num_features > 0, "orb.num_features", "> 0");
  require(num_levels >= 1 && num_levels <= 32, "orb.num_levels", "in [1, 32]");
  require(scale_factor > 1.0F && scale_factor <= 4.0F, "orb.scale_factor", "in (1, 4]");
  require(fast_threshold >= 1 && fast_threshold <= 254, "orb.fast_threshold", "in [1, 254]");
  require(fast_min_threshold >= 1 && fast_min_threshold <= fast_threshold, "orb.fast_min_threshold",
          "in [1, fast_threshold]");
  require(cell_size >= 8, "orb.cell_size", ">= 8");
  require(features_per_node >= 1, "orb.features_per_node", ">= 1");
  require(spread_fraction > 0.0 && spread_fraction <= 1.0, "orb.spread_fraction", "a fraction in (0, 1]");
  require(patch_size >= 5 && patch_size % 2 == 1, "orb.patch_size", "odd and >= 5");
  require(orientation_radius >= 1, "orb.orientation_radius", ">= 1");
  require(edge_threshold >= std::max(patch_size / 2, orientation_radius) + 1 && edge_threshold >= 4,
          "orb.edge_threshold", "> max(patch_size / 2, orientation_radius) and >= 4");
  require(blur_size >= 1 && blur_size % 2 == 1, "orb.blur_size", "odd and >= 1");
  require(blur_sigma > 0.0, "orb.blur_sigma", "> 0");
}

namespace {

// SplitMix64: a tiny, fully specified generator, so the pattern does not depend on the standard
// library's distributions (which differ between implementations).
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31U);
  }
  // Uniform in (0, 1).
  double uniform() { return (static_cast<double>(next() >> 11U) + 0.5) * (1.0 / 9007199254740992.0); }

 private:
  std::uint64_t state_;
};

#if defined(__SSE2__)
inline __m128i load16(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }

inline int horizontal_sum(__m128i v) {
  v = _mm_add_epi32(v, _mm_shuffle_epi32(v, 0x4E));
  v = _mm_add_epi32(v, _mm_shuffle_epi32(v, 0xB1));
  return _mm_cvtsi128_si32(v);
}

// Intensity-centroid moments over the disc of radius <= 15: each row pair (+v, -v) as 32 bytes
// (u = -16..15) masked to the disc, widened to 16 bits; m10 by multiply-add with u, m01 with v.
// `masks` holds 32 bytes per row offset v (0xFF where |u| <= half width). Needs 16 px left and 15 px
// right of the centre inside the image.
inline void centroid_moments_sse2(const std::uint8_t* centre, int step, int radius, const std::uint8_t* masks,
                                  int& m10, int& m01) {
  const __m128i zero = _mm_setzero_si128();
  const __m128i u0 = _mm_setr_epi16(-16, -15, -14, -13, -12, -11, -10, -9);
  const __m128i u1 = _mm_setr_epi16(-8, -7, -6, -5, -4, -3, -2, -1);
  const __m128i u2 = _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7);
  const __m128i u3 = _mm_setr_epi16(8, 9, 10, 11, 12, 13, 14, 15);
  __m128i acc10 = zero, acc01 = zero;
  for (int v = 0; v <= radius; ++v) {
    const __m128i mask_lo = load16(masks + 32 * v), mask_hi = load16(masks + 32 * v + 16);
    const std::uint8_t* below = centre + v * step;
    const __m128i b_lo = _mm_and_si128(load16(below - 16), mask_lo), b_hi = _mm_and_si128(load16(below), mask_hi);
    __m128i a_lo = zero, a_hi = zero;
    if (v > 0) {
      const std::uint8_t* above = centre - v * step;
      a_lo = _mm_and_si128(load16(above - 16), mask_lo);
      a_hi = _mm_and_si128(load16(above), mask_hi);
    }
    const __m128i b0 = _mm_unpacklo_epi8(b_lo, zero), b1 = _mm_unpackhi_epi8(b_lo, zero);
    const __m128i b2 = _mm_unpacklo_epi8(b_hi, zero), b3 = _mm_unpackhi_epi8(b_hi, zero);
    const __m128i a0 = _mm_unpacklo_epi8(a_lo, zero), a1 = _mm_unpackhi_epi8(a_lo, zero);
    const __m128i a2 = _mm_unpacklo_epi8(a_hi, zero), a3 = _mm_unpackhi_epi8(a_hi, zero);
    acc10 = _mm_add_epi32(acc10, _mm_add_epi32(_mm_add_epi32(_mm_madd_epi16(_mm_add_epi16(b0, a0), u0),
                                                             _mm_madd_epi16(_mm_add_epi16(b1, a1), u1)),
                                               _mm_add_epi32(_mm_madd_epi16(_mm_add_epi16(b2, a2), u2),
                                                             _mm_madd_epi16(_mm_add_epi16(b3, a3), u3))));
    if (v > 0) {
      const __m128i diff = _mm_add_epi16(_mm_add_epi16(_mm_sub_epi16(b0, a0), _mm_sub_epi16(b1, a1)),
                                         _mm_add_epi16(_mm_sub_epi16(b2, a2), _mm_sub_epi16(b3, a3)));
      acc01 = _mm_add_epi32(acc01, _mm_madd_epi16(diff, _mm_set1_epi16(static_cast<short>(v))));
    }
  }
  m10 = horizontal_sum(acc10);
  m01 = horizontal_sum(acc01);
}
#endif

}  // namespace

std::vector<BriefPair> make_brief_candidates(int patch_size, int count) {
  const double radius = patch_size / 2;  // integer half size: rotated, rounded points stay inside
  const double sigma = patch_size / 5.0;
  SplitMix64 rng(0x5247424C4F524231ULL);  // "RGBLORB1"
  auto gaussian_point = [&]() {
    for (;;) {
      // Box-Muller: two independent N(0, sigma) coordinates, redrawn until inside the disc.
      const double r = std::sqrt(-2.0 * std::log(rng.uniform())) * sigma;
      const double t = 2.0 * 3.14159265358979323846 * rng.uniform();
      const double x = r * std::cos(t), y = r * std::sin(t);
      if (x * x + y * y <= radius * radius) return std::pair{static_cast<float>(x), static_cast<float>(y)};
    }
  };
  std::vector<BriefPair> pattern;
  pattern.reserve(static_cast<std::size_t>(count));
  while (static_cast<int>(pattern.size()) < count) {
    const auto [x1, y1] = gaussian_point();
    const auto [x2, y2] = gaussian_point();
    // A test between (nearly) the same pixel carries no information.
    if ((x1 - x2) * (x1 - x2) + (y1 - y2) * (y1 - y2) < 4.0F) continue;
    pattern.push_back({x1, y1, x2, y2});
  }
  return pattern;
}

namespace {
#include "brief_pattern_indices.inc"
}  // namespace

std::vector<BriefPair> make_brief_pattern(int patch_size) {
  if (patch_size != 31 || kLearnedPairs.empty()) return make_brief_candidates(patch_size, 256);
  const auto pool = make_brief_candidates(31, kLearnedPoolSize);
  std::vector<BriefPair> pattern;
  pattern.reserve(kLearnedPairs.size());
  for (const auto index : kLearnedPairs) pattern.push_back(pool[index]);
  return pattern;
}

OrbExtractor::OrbExtractor(const OrbOptions& options) : options_(options) {
  options_.validate();
  const int levels = options_.num_levels;
  scales_.resize(static_cast<std::size_t>(levels));
  budgets_.resize(static_cast<std::size_t>(levels));
  scales_[0] = 1.0F;
  for (int l = 1; l < levels; ++l) {
    scales_[static_cast<std::size_t>(l)] = scales_[static_cast<std::size_t>(l) - 1] * options_.scale_factor;
  }
  // Geometric series in 1/scale: level l gets N (1 - f) / (1 - f^L) f^l, the last level the rest.
  const double f = 1.0 / options_.scale_factor;
  double per_level = options_.num_features * (1.0 - f) / (1.0 - std::pow(f, levels));
  int assigned = 0;
  for (int l = 0; l < levels - 1; ++l) {
    budgets_[static_cast<std::size_t>(l)] = static_cast<int>(std::lround(per_level));
    assigned += budgets_[static_cast<std::size_t>(l)];
    per_level *= f;
  }
  budgets_[static_cast<std::size_t>(levels) - 1] = std::max(0, options_.num_features - assigned);

  const std::vector<BriefPair> pattern = make_brief_pattern(options_.patch_size);
  const std::size_t n = pattern.size();
  pattern_soa_.resize(n * 4);
  for (std::size_t i = 0; i < n; ++i) {
    pattern_soa_[i] = pattern[i].x1;
    pattern_soa_[n + i] = pattern[i].y1;
    pattern_soa_[2 * n + i] = pattern[i].x2;
    pattern_soa_[3 * n + i] = pattern[i].y2;
  }
  levels_.resize(static_cast<std::size_t>(levels));
  for (auto& level : levels_) level.pattern_offsets.resize(n * 2);
  const int r = options_.orientation_radius;
  disc_half_width_.resize(static_cast<std::size_t>(r) + 1);
  for (int v = 0; v <= r; ++v) {
    disc_half_width_[static_cast<std::size_t>(v)] =
        static_cast<int>(std::floor(std::sqrt(static_cast<double>(r * r - v * v)) + 0.5));
  }
  // Row masks for the SIMD centroid: 32 bytes per row, u = -16..15 (needs r <= 15 and 16 px of border).
  if (r <= 15 && options_.edge_threshold >= 16) {
    disc_masks_.assign(static_cast<std::size_t>(r + 1) * 32, 0);
    for (int v = 0; v <= r; ++v) {
      for (int u = -16; u < 16; ++u) {
        if (std::abs(u) <= disc_half_width_[static_cast<std::size_t>(v)]) {
          disc_masks_[static_cast<std::size_t>(v * 32 + u + 16)] = 0xFF;
        }
      }
    }
  }
  pyramid_.resize(static_cast<std::size_t>(levels));
}

LevelMap LevelMap::between(cv::Size level0, cv::Size level) noexcept {
  LevelMap m;
  if (level.width <= 0 || level.height <= 0 || level == level0) return m;
  m.ax = static_cast<float>(level0.width) / static_cast<float>(level.width);
  m.ay = static_cast<float>(level0.height) / static_cast<float>(level.height);
  m.bx = 0.5F * m.ax - 0.5F;
  m.by = 0.5F * m.ay - 0.5F;
  return m;
}

void OrbExtractor::build_pyramid(const cv::Mat& gray) {
  pyramid_[0] = gray;
  level_maps_.assign(static_cast<std::size_t>(options_.num_levels), LevelMap{});
  for (int l = 1; l < options_.num_levels; ++l) {
    const float s = scales_[static_cast<std::size_t>(l)];
    const cv::Size size(static_cast<int>(std::lround(static_cast<float>(gray.cols) / s)),
                        static_cast<int>(std::lround(static_cast<float>(gray.rows) / s)));
    cv::Mat& dst = pyramid_[static_cast<std::size_t>(l)];
    if (size.width <= 0 || size.height <= 0) {
      dst.release();
      continue;
    }
    if (dst.size() != size || dst.type() != CV_8UC1 || dst.data == gray.data) dst.create(size, CV_8UC1);
    // Resizing the previous level is cheaper than resizing level 0 and is what ORB-SLAM does.
    cv::resize(pyramid_[static_cast<std::size_t>(l) - 1], dst, size, 0, 0, cv::INTER_LINEAR);
    level_maps_[static_cast<std::size_t>(l)] = LevelMap::between(gray.size(), size);
  }
}

// FAST once over the level at the low threshold (scores kept), then per cell: the corners scoring
// >= fast_threshold where the cell has any, else all of them (>= fast_min_threshold).
void OrbExtractor::detect_level(int level) {
  Level& lv = levels_[static_cast<std::size_t>(level)];
  auto& candidates = lv.candidates;
  auto& fast = lv.fast;
  auto& cell_strong = lv.cell_strong;
  candidates.clear();
  const cv::Mat& img = pyramid_[static_cast<std::size_t>(level)];
  const int edge = options_.edge_threshold;
  const int width = img.cols - 2 * edge, height = img.rows - 2 * edge;  // where corners may lie
  if (img.empty() || width <= 0 || height <= 0) return;
  detail::detect_fast(img, cv::Rect(edge, edge, width, height), options_.fast_min_threshold, lv.fast_scores, fast);
  if (fast.empty()) return;

  const int cols = std::max(1, width / options_.cell_size), rows = std::max(1, height / options_.cell_size);
  // Cell of a corner, by integer arithmetic: cells split the region as evenly as possible.
  // (tabulated per column and row: two integer divisions per corner cost more than the lookups)
  auto& cell_col = lv.cell_col;
  auto& cell_row = lv.cell_row;
  cell_col.resize(static_cast<std::size_t>(width));
  cell_row.resize(static_cast<std::size_t>(height));
  for (int x = 0; x < width; ++x) cell_col[static_cast<std::size_t>(x)] = x * cols / width;
  for (int y = 0; y < height; ++y) cell_row[static_cast<std::size_t>(y)] = y * rows / height * cols;
  auto cell_of = [&](const detail::FastCorner& k) {
    return static_cast<std::size_t>(cell_row[static_cast<std::size_t>(k.y - edge)] +
                                    cell_col[static_cast<std::size_t>(k.x - edge)]);
  };
  cell_strong.assign(static_cast<std::size_t>(cols * rows), 0);
  const int strong = options_.fast_threshold;
  // Both loops branch-free: whether a corner is strong is a coin flip to a branch predictor.
  for (const auto& k : fast) cell_strong[cell_of(k)] |= static_cast<unsigned char>(k.score >= strong);
  candidates.resize(fast.size());
  std::size_t kept = 0;
  for (const auto& k : fast) {
    candidates[kept] = {static_cast<float>(k.x), static_cast<float>(k.y), static_cast<float>(k.score)};
    kept += static_cast<std::size_t>(k.score >= strong) | static_cast<std::size_t>(cell_strong[cell_of(k)] == 0);
  }
  candidates.resize(kept);
}

// Quadtree over the candidates: split nodes (breadth first) until there are target / per_node nodes or
// every node holds one corner; when a full round would overshoot, split the most populated nodes
// first. Each node then contributes its per_node strongest corners (ties: by position), and if that
// is more than `target` the strongest of them are kept.
void OrbExtractor::distribute(int target, Level& level) {
  std::vector<Candidate>& candidates = level.candidates;
  std::vector<Candidate>& selected = level.selected;
  std::vector<Candidate>& bucketed = level.bucketed;
  std::vector<Candidate>& leftover = level.leftover;
  std::vector<Node>& nodes = level.nodes;
  std::vector<Node>& next_nodes = level.next_nodes;
  selected.clear();
  if (candidates.empty() || target <= 0) return;
  const auto n = static_cast<int>(candidates.size());
  if (n <= target) {
    selected.assign(candidates.begin(), candidates.end());
    return;
  }
  // The quadtree places spread_fraction of the target, aiming at that / per_node nodes, each
  // contributing its per_node strongest corners; the rest of the target goes to the strongest corners
  // left over, wherever they are.
  const int spread_target = std::max(1, static_cast<int>(std::lround(options_.spread_fraction * target)));
  const int per_node = options_.features_per_node;
  const int target_nodes = (spread_target + per_node - 1) / per_node;
  float min_x = candidates[0].x, max_x = min_x, min_y = candidates[0].y, max_y = min_y;
  for (const auto& c : candidates) {
    min_x = std::min(min_x, c.x);
    max_x = std::max(max_x, c.x);
    min_y = std::min(min_y, c.y);
    max_y = std::max(max_y, c.y);
  }
  max_x += 1.0F;  // half-open boxes
  max_y += 1.0F;
  // Start from roughly square root nodes side by side, as wide images would otherwise split badly.
  const int roots = std::max(1, static_cast<int>(std::lround((max_x - min_x) / (max_y - min_y))));
  const float root_w = (max_x - min_x) / static_cast<float>(roots);
  nodes.clear();
  {
    // Stable bucketing into the roots (candidates arrive in row-major order, which is kept).
    auto root_of = [&](const Candidate& c) {
      return std::min(roots - 1, static_cast<int>((c.x - min_x) / root_w));
    };
    std::vector<int>& counts = level.root_counts;
    counts.assign(static_cast<std::size_t>(roots) + 1, 0);
    for (const auto& c : candidates) ++counts[static_cast<std::size_t>(root_of(c)) + 1];
    for (std::size_t r = 1; r < counts.size(); ++r) counts[r] += counts[r - 1];
    bucketed.resize(candidates.size());
    std::vector<int> fill(counts.begin(), counts.end() - 1);
    for (const auto& c : candidates) {
      bucketed[static_cast<std::size_t>(fill[static_cast<std::size_t>(root_of(c))]++)] = c;
    }
    candidates.swap(bucketed);
    for (int r = 0; r < roots; ++r) {
      const int begin = counts[static_cast<std::size_t>(r)], end = counts[static_cast<std::size_t>(r) + 1];
      if (end > begin) {
        const float bx0 = min_x + root_w * static_cast<float>(r);
        nodes.push_back({bx0, min_y, r == roots - 1 ? max_x : bx0 + root_w, max_y, begin, end});
      }
    }
  }
  auto splittable = [](const Node& node) {
    return node.end - node.begin > 1 && node.x1 - node.x0 > 1.0F && node.y1 - node.y0 > 1.0F;
  };
  // Only which quadrant a corner falls in matters (the order inside a node does not: a node's corners
  // are ranked by a total order), so the split is a branch-free counting sort over the 4 quadrants
  // (top left, top right, bottom left, bottom right): the comparisons are coin flips a branch
  // predictor cannot learn.
  std::vector<Candidate>& scratch = level.bucketed;
  auto split = [&](const Node& node, std::vector<Node>& out) {
    const float xm = 0.5F * (node.x0 + node.x1), ym = 0.5F * (node.y0 + node.y1);
    const auto quadrant = [xm, ym](const Candidate& c) {
      return static_cast<std::size_t>(c.y >= ym) * 2U + static_cast<std::size_t>(c.x >= xm);
    };
    const auto first = static_cast<std::size_t>(node.begin), last = static_cast<std::size_t>(node.end);
    std::array<int, 4> count{};
    for (std::size_t i = first; i < last; ++i) ++count[quadrant(candidates[i])];
    std::array<std::size_t, 4> fill{};
    fill[0] = first;
    for (std::size_t q = 1; q < 4; ++q) fill[q] = fill[q - 1] + static_cast<std::size_t>(count[q - 1]);
    const std::array<std::size_t, 4> start = fill;
    for (std::size_t i = first; i < last; ++i) scratch[fill[quadrant(candidates[i])]++] = candidates[i];
    const auto index = [](std::size_t i) { return static_cast<int>(i); };
    const Node children[4] = {{node.x0, node.y0, xm, ym, index(start[0]), index(start[1])},
                              {xm, node.y0, node.x1, ym, index(start[1]), index(start[2])},
                              {node.x0, ym, xm, node.y1, index(start[2]), index(start[3])},
                              {xm, ym, node.x1, node.y1, index(start[3]), index(last)}};
    for (const Node& c : children) {
      if (c.end > c.begin) out.push_back(c);
    }
  };
  // A round writes every node's corners into the scratch at the same positions (split nodes by
  // quadrant, the others as they are), then the two buffers swap.
  auto carry_over = [&](const Node& node, std::vector<Node>& out) {
    std::copy(candidates.begin() + node.begin, candidates.begin() + node.end, scratch.begin() + node.begin);
    out.push_back(node);
  };
  for (;;) {
    if (static_cast<int>(nodes.size()) >= target_nodes) break;
    const auto expandable = static_cast<int>(std::count_if(nodes.begin(), nodes.end(), splittable));
    if (expandable == 0) break;
    if (static_cast<int>(nodes.size()) + 3 * expandable < target_nodes) {
      next_nodes.clear();
      for (const Node& node : nodes) {
        if (splittable(node)) {
          split(node, next_nodes);
        } else {
          carry_over(node, next_nodes);
        }
      }
      nodes.swap(next_nodes);
      candidates.swap(scratch);
      continue;
    }
    // Last round: split the most populated nodes first, stopping as soon as the target is reached.
    std::stable_sort(nodes.begin(), nodes.end(),
                     [](const Node& a, const Node& b) { return a.end - a.begin > b.end - b.begin; });
    next_nodes.clear();
    std::size_t i = 0;
    for (; i < nodes.size(); ++i) {
      const std::size_t total = next_nodes.size() + (nodes.size() - i);
      if (static_cast<int>(total) >= target_nodes) break;
      if (splittable(nodes[i])) {
        split(nodes[i], next_nodes);
      } else {
        carry_over(nodes[i], next_nodes);
      }
    }
    for (; i < nodes.size(); ++i) carry_over(nodes[i], next_nodes);
    nodes.swap(next_nodes);
    candidates.swap(scratch);
  }
  const auto stronger = [](const Candidate& a, const Candidate& b) {
    if (a.response != b.response) return a.response > b.response;
    return a.y < b.y || (a.y == b.y && a.x < b.x);  // ties by position: independent of partition order
  };
  selected.reserve(nodes.size() * static_cast<std::size_t>(per_node));
  for (const Node& node : nodes) {
    auto* first = candidates.data() + node.begin;
    auto* last = candidates.data() + node.end;
    const int keep = std::min(per_node, node.end - node.begin);
    std::partial_sort(first, first + keep, last, stronger);
    selected.insert(selected.end(), first, first + keep);
  }
  leftover.clear();
  if (static_cast<int>(selected.size()) > spread_target) {
    std::stable_sort(selected.begin(), selected.end(),
                     [](const Candidate& a, const Candidate& b) { return a.response > b.response; });
    leftover.assign(selected.begin() + spread_target, selected.end());
    selected.resize(static_cast<std::size_t>(spread_target));
  }
  const int rest = target - static_cast<int>(selected.size());
  if (rest <= 0) return;
  // The rest from the corners the quadtree did not take: those the trimming above dropped and
  // everything behind each node's kept ones.
  for (const Node& node : nodes) {
    const int keep = std::min(per_node, node.end - node.begin);
    leftover.insert(leftover.end(), candidates.begin() + node.begin + keep, candidates.begin() + node.end);
  }
  const auto take = std::min(static_cast<std::size_t>(rest), leftover.size());
  if (take == 0) return;
  // Responses are FAST scores (whole numbers up to 255): a histogram finds the weakest response the
  // `take` strongest can have, and only corners at least that strong are ranked.
  std::array<int, 256> histogram{};
  for (const Candidate& c : leftover) ++histogram[static_cast<std::size_t>(c.response)];
  std::size_t weakest = 255, at_least = static_cast<std::size_t>(histogram[255]);
  while (at_least < take) at_least += static_cast<std::size_t>(histogram[--weakest]);
  const auto floor = static_cast<float>(weakest);
  std::size_t kept = 0;
  for (const Candidate& c : leftover) {  // branch-free compaction, in place
    leftover[kept] = c;
    kept += c.response >= floor ? 1 : 0;
  }
  leftover.resize(kept);
  std::partial_sort(leftover.begin(), leftover.begin() + static_cast<std::ptrdiff_t>(take), leftover.end(), stronger);
  selected.insert(selected.end(), leftover.begin(), leftover.begin() + static_cast<std::ptrdiff_t>(take));
}

void OrbExtractor::describe_level(int level) {
  Level& lv = levels_[static_cast<std::size_t>(level)];
  const std::vector<Candidate>& selected = lv.selected;
  std::vector<Keypoint>& keypoints = lv.keypoints;
  std::vector<Descriptor>& descriptors = lv.descriptors;
  std::vector<int>& offsets = lv.pattern_offsets;
  cv::Mat& blurred = lv.blurred;
  keypoints.clear();
  descriptors.clear();
  if (selected.empty()) return;
  keypoints.reserve(selected.size());
  descriptors.reserve(selected.size());
  const cv::Mat& img = pyramid_[static_cast<std::size_t>(level)];
  detail::smooth_for_brief(img, blurred, options_.blur_size, options_.blur_sigma, lv.smooth_row, lv.smooth_rows);
  const float scale = scales_[static_cast<std::size_t>(level)];
  const LevelMap& to_image = level_maps_[static_cast<std::size_t>(level)];
  const int r = options_.orientation_radius;
  const auto step = static_cast<int>(img.step1());
  const auto blurred_step = static_cast<int>(blurred.step1());
  constexpr float kRadToDeg = 180.0F / 3.14159265358979323846F;
  constexpr float kDegToRad = 3.14159265358979323846F / 180.0F;
  for (const Candidate& c : selected) {
    const int cx = static_cast<int>(c.x), cy = static_cast<int>(c.y);
    // Intensity centroid over the disc: rows +v and -v together.
    const std::uint8_t* centre = img.ptr<std::uint8_t>(cy) + cx;
    int m10 = 0, m01 = 0;
#if defined(__SSE2__)
    if (!disc_masks_.empty()) {
      centroid_moments_sse2(centre, step, r, disc_masks_.data(), m10, m01);
    } else
#endif
    {
    for (int u = -r; u <= r; ++u) m10 += u * centre[u];
    for (int v = 1; v <= r; ++v) {
      const int w = disc_half_width_[static_cast<std::size_t>(v)];
      const std::uint8_t* below = centre + v * step;
      const std::uint8_t* above = centre - v * step;
      int sum_diff = 0, sum_x = 0;
      for (int u = -w; u <= w; ++u) {
        const int b = below[u], a = above[u];
        sum_diff += b - a;
        sum_x += u * (b + a);
      }
      m01 += v * sum_diff;
      m10 += sum_x;
    }
    }
    float angle = std::atan2(static_cast<float>(m01), static_cast<float>(m10)) * kRadToDeg;
    if (angle < 0.0F) angle += 360.0F;
    if (angle >= 360.0F) angle -= 360.0F;

    // Rotate the pattern into the keypoint's frame, then compare smoothed intensities.
    const float ca = std::cos(angle * kDegToRad), sa = std::sin(angle * kDegToRad);
    detail::rotate_pattern(pattern_soa_, sa, ca, blurred_step, offsets);
    Descriptor d{};
    detail::brief_bits(blurred.ptr<std::uint8_t>(cy) + cx, offsets, d.data());
    Keypoint k;
    k.x = to_image.image_x(c.x);
    k.y = to_image.image_y(c.y);
    k.angle = angle;
    k.response = c.response;
    k.size = static_cast<float>(options_.patch_size) * scale;
    k.level = level;
    keypoints.push_back(k);
    descriptors.push_back(d);
  }
}

void OrbExtractor::extract(const cv::Mat& gray, std::vector<Keypoint>& keypoints,
                           std::vector<Descriptor>& descriptors, TaskPool* pool) {
  require(!gray.empty() && gray.type() == CV_8UC1, "orb.image", "a non-empty 8-bit single-channel image");
  keypoints.clear();
  descriptors.clear();
  keypoints.reserve(static_cast<std::size_t>(options_.num_features));
  descriptors.reserve(static_cast<std::size_t>(options_.num_features));
  build_pyramid(gray);
  const auto levels = static_cast<std::size_t>(options_.num_levels);
  const auto each_level = [&](auto&& fn) {
    parallel_for(pool, levels, [&](std::size_t l) { fn(static_cast<int>(l)); });
  };
  each_level([this](int l) { detect_level(l); });
  // A level keeps exactly its budget when it has at least that many candidates; only a level that
  // falls short passes budget on. When none does, the levels are independent (the usual case).
  bool independent = true;
  for (std::size_t l = 0; l < levels; ++l) {
    independent = independent && static_cast<int>(levels_[l].candidates.size()) >= budgets_[l];
  }
  if (independent) {
    each_level([this](int l) {
      distribute(budgets_[static_cast<std::size_t>(l)], levels_[static_cast<std::size_t>(l)]);
      describe_level(l);
    });
  } else {
    int carry = 0;  // a level's unused budget goes to the next one
    for (std::size_t l = 0; l < levels; ++l) {
      const int target = budgets_[l] + carry;
      distribute(target, levels_[l]);
      carry = target - static_cast<int>(levels_[l].selected.size());
    }
    each_level([this](int l) { describe_level(l); });
  }
  for (const Level& lv : levels_) {
    keypoints.insert(keypoints.end(), lv.keypoints.begin(), lv.keypoints.end());
    descriptors.insert(descriptors.end(), lv.descriptors.begin(), lv.descriptors.end());
  }
}

}  // namespace rgbl
