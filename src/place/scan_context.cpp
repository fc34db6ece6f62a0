#include "rgbl/place/scan_context.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>

namespace rgbl {

void ScanContextOptions::validate() const {
  // the upper bounds keep rings * sectors far from int overflow; finer grids have too few points per cell
  require(rings >= 1 && rings <= 1000, "scan_context.rings", "in [1, 1000]");
  require(sectors >= 2 && sectors <= 3600, "scan_context.sectors", "in [2, 3600]");
  require(min_range >= 0.0, "scan_context.min_range", ">= 0 m");
  require(max_range > min_range && std::isfinite(max_range), "scan_context.max_range", "finite and > min_range");
  require(std::isfinite(height_offset), "scan_context.height_offset", "a finite height in m");
}

ScanContext::ScanContext(int rings, int sectors)
    : rings_(rings), sectors_(sectors), cells_(static_cast<std::size_t>(rings * sectors), 0.0F),
      ring_key_(static_cast<std::size_t>(rings), 0.0F) {}

void ScanContext::update_ring_key() {
  for (int r = 0; r < rings_; ++r) {
    int occupied = 0;
    for (int s = 0; s < sectors_; ++s) occupied += cell(r, s) > 0.0F ? 1 : 0;
    ring_key_[static_cast<std::size_t>(r)] = static_cast<float>(occupied) / static_cast<float>(sectors_);
  }
}

ScanContext make_scan_context(PointCloudView scan, const ScanContextOptions& options) {
  options.validate();
  ScanContext context(options.rings, options.sectors);
  // Ranges compared squared, so points outside the annulus cost no sqrt or atan2; sqrt, not hypot, whose
  // overflow care buys nothing at LiDAR ranges and costs time in the hottest loop.
  const double min_sq = options.min_range * options.min_range;
  const double max_sq = options.max_range * options.max_range;
  const double rings_per_m = options.rings / (options.max_range - options.min_range);
  const double sectors_per_rad = options.sectors / (2.0 * std::numbers::pi);
  for (const LidarPoint& p : scan) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const double x = p.x, y = p.y;
    const double range_sq = x * x + y * y;
    if (range_sq < min_sq || range_sq >= max_sq) continue;
    const int ring =
        std::min(options.rings - 1, static_cast<int>((std::sqrt(range_sq) - options.min_range) * rings_per_m));
    int sector = static_cast<int>((std::atan2(y, x) + std::numbers::pi) * sectors_per_rad);
    if (sector >= options.sectors) sector = 0;  // azimuth +pi is -pi: straight behind, sector 0
    const float height = std::max(0.0F, static_cast<float>(p.z + options.height_offset));
    float& c = context.cell(ring, sector);
    c = std::max(c, height);
  }
  context.update_ring_key();
  return context;
}

namespace {

// Cells copied column by column with each column's norm: the shift search walks columns, and a cosine
// is then one contiguous dot product. Doubles, so a column compared with itself gives 1 to ~1e-16.
struct Columns {
  int rings = 0, sectors = 0;
  std::vector<double> values;  // sector-major
  std::vector<double> norm;    // 0: the column holds no point
  std::vector<double> key;     // the sector key: the column's mean over rings

  explicit Columns(const ScanContext& c)
      : rings(c.rings()), sectors(c.sectors()), values(static_cast<std::size_t>(rings * sectors)),
        norm(static_cast<std::size_t>(sectors)), key(static_cast<std::size_t>(sectors)) {
    for (int s = 0; s < sectors; ++s) {
      double sum = 0.0, sum_sq = 0.0;
      for (int r = 0; r < rings; ++r) {
        const double v = c.cell(r, s);
        values[static_cast<std::size_t>(s * rings + r)] = v;
        sum += v;
        sum_sq += v * v;
      }
      norm[static_cast<std::size_t>(s)] = std::sqrt(sum_sq);
      key[static_cast<std::size_t>(s)] = sum / rings;
    }
  }
  const double* column(int s) const { return values.data() + static_cast<std::ptrdiff_t>(s) * rings; }
};

void check_sizes(const ScanContext& query, const ScanContext& candidate) {
  if (query.rings() != candidate.rings() || query.sectors() != candidate.sectors()) {
    throw ConfigError("scan_context", fmt::format("descriptors of one size (query {}x{}, candidate {}x{})",
                                                  query.rings(), query.sectors(), candidate.rings(),
                                                  candidate.sectors()));
  }
}

// Mean (1 - cosine) over the columns occupied in both, query column s against candidate column
// s + shift; nullopt when no column is occupied in both.
std::optional<double> distance_at(const Columns& q, const Columns& c, int shift) {
  double sum = 0.0;
  int columns = 0;
  for (int s = 0; s < q.sectors; ++s) {
    const int t = s + shift < q.sectors ? s + shift : s + shift - q.sectors;
    const double nq = q.norm[static_cast<std::size_t>(s)], nc = c.norm[static_cast<std::size_t>(t)];
    if (nq == 0.0 || nc == 0.0) continue;
    const double* a = q.column(s);
    const double* b = c.column(t);
    double dot = 0.0;
    for (int r = 0; r < q.rings; ++r) dot += a[r] * b[r];
    sum += 1.0 - dot / (nq * nc);
    ++columns;
  }
  if (columns == 0) return std::nullopt;
  return sum / columns;
}

// Best of the shifts marked in `search` (all when empty); the lowest shift wins a tie.
ScanContextMatch best_shift(const Columns& q, const Columns& c, const std::vector<char>& search) {
  ScanContextMatch best;
  for (int shift = 0; shift < q.sectors; ++shift) {
    if (!search.empty() && search[static_cast<std::size_t>(shift)] == 0) continue;
    const std::optional<double> d = distance_at(q, c, shift);
    if (d && *d < best.distance) {
      best.distance = *d;
      best.sector_shift = shift;
    }
  }
  // shift k: query azimuth a sits where the candidate has a + k sectors
  const int signed_shift = best.sector_shift > q.sectors / 2 ? best.sector_shift - q.sectors : best.sector_shift;
  best.yaw = signed_shift * 2.0 * std::numbers::pi / q.sectors;
  return best;
}

constexpr int kKeyAlignments = 3;  // best sector-key alignments searched in full
constexpr int kShiftRadius = 2;    // sectors searched either side of each: the keys blur a part-sector turn

ScanContextMatch compare_coarse_to_fine(const Columns& q, const Columns& c) {
  const int sectors = q.sectors;
  std::vector<double> key_distance(static_cast<std::size_t>(sectors));
  for (int shift = 0; shift < sectors; ++shift) {
    double d = 0.0;
    for (int s = 0; s < sectors; ++s) {
      const int t = s + shift < sectors ? s + shift : s + shift - sectors;
      d += std::abs(q.key[static_cast<std::size_t>(s)] - c.key[static_cast<std::size_t>(t)]);
    }
    key_distance[static_cast<std::size_t>(shift)] = d;
  }
  std::vector<int> order(static_cast<std::size_t>(sectors));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return key_distance[static_cast<std::size_t>(a)] < key_distance[static_cast<std::size_t>(b)];
  });
  std::vector<char> search(static_cast<std::size_t>(sectors), 0);
  const double best_key = key_distance[static_cast<std::size_t>(order.front())];
  for (int i = 0; i < sectors; ++i) {
    const int centre = order[static_cast<std::size_t>(i)];
    // ties with the best are all kept: a symmetric scene must not hide the exact alignment
    if (i >= kKeyAlignments && key_distance[static_cast<std::size_t>(centre)] > best_key) break;
    for (int d = -kShiftRadius; d <= kShiftRadius; ++d) {
      search[static_cast<std::size_t>(((centre + d) % sectors + sectors) % sectors)] = 1;
    }
  }
  return best_shift(q, c, search);
}

}  // namespace

ScanContextMatch compare(const ScanContext& query, const ScanContext& candidate) {
  check_sizes(query, candidate);
  return compare_coarse_to_fine(Columns(query), Columns(candidate));
}

ScanContextMatch compare_all_shifts(const ScanContext& query, const ScanContext& candidate) {
  check_sizes(query, candidate);
  return best_shift(Columns(query), Columns(candidate), {});
}

void ScanContextDatabase::add(std::size_t id, ScanContext context) {
  entries_.push_back(Entry{id, std::move(context)});
}

std::vector<ScanContextDatabase::Candidate> ScanContextDatabase::query(const ScanContext& context,
                                                                      std::size_t ring_key_neighbours,
                                                                      const std::function<bool(std::size_t)>& allowed) const {
  std::vector<std::pair<double, std::size_t>> by_key;  // (squared ring-key distance, entry index)
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    if (allowed && !allowed(entries_[i].id)) continue;
    const auto& a = context.ring_key();
    const auto& b = entries_[i].context.ring_key();
    if (a.size() != b.size()) continue;
    double d = 0.0;
    for (std::size_t r = 0; r < a.size(); ++r) d += static_cast<double>(a[r] - b[r]) * (a[r] - b[r]);
    by_key.emplace_back(d, i);
  }
  const std::size_t keep = std::min(ring_key_neighbours, by_key.size());
  std::partial_sort(by_key.begin(), by_key.begin() + static_cast<std::ptrdiff_t>(keep), by_key.end());
  std::vector<Candidate> out;
  out.reserve(keep);
  const Columns query_columns(context);
  for (std::size_t k = 0; k < keep; ++k) {
    const Entry& e = entries_[by_key[k].second];
    check_sizes(context, e.context);
    out.push_back(Candidate{e.id, compare_coarse_to_fine(query_columns, Columns(e.context))});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Candidate& a, const Candidate& b) { return a.match.distance < b.match.distance; });
  return out;
}

}  // namespace rgbl
