#include "rgbl/place/scan_context.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rgbl {

void ScanContextOptions::validate() const {
  require(rings >= 1, "scan_context.rings", ">= 1");
  require(sectors >= 2, "scan_context.sectors", ">= 2");
  require(min_range >= 0.0, "scan_context.min_range", ">= 0 m");
  require(max_range > min_range, "scan_context.max_range", "> min_range");
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
  const double ring_step = (options.max_range - options.min_range) / options.rings;
  const double sector_step = 2.0 * M_PI / options.sectors;
  for (const LidarPoint& p : scan) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const double range = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
    if (range < options.min_range || range >= options.max_range) continue;
    const int ring = std::min(options.rings - 1, static_cast<int>((range - options.min_range) / ring_step));
    const double azimuth = std::atan2(static_cast<double>(p.y), static_cast<double>(p.x));
    const int sector = std::clamp(static_cast<int>(std::floor((azimuth + M_PI) / sector_step)), 0, options.sectors - 1);
    const float height = std::max(0.0F, static_cast<float>(p.z + options.height_offset));
    float& c = context.cell(ring, sector);
    c = std::max(c, height);
  }
  context.update_ring_key();
  return context;
}

ScanContextMatch compare(const ScanContext& query, const ScanContext& candidate) {
  if (query.rings() != candidate.rings() || query.sectors() != candidate.sectors()) {
    throw ConfigError("scan_context", fmt::format("descriptors of one size (query {}x{}, candidate {}x{})",
                                                  query.rings(), query.sectors(), candidate.rings(),
                                                  candidate.sectors()));
  }
  const int rings = query.rings();
  const int sectors = query.sectors();
  // Column norms once; a column with norm 0 holds no point.
  std::vector<double> norm_q(static_cast<std::size_t>(sectors), 0.0), norm_c(static_cast<std::size_t>(sectors), 0.0);
  for (int s = 0; s < sectors; ++s) {
    for (int r = 0; r < rings; ++r) {
      norm_q[static_cast<std::size_t>(s)] += static_cast<double>(query.cell(r, s)) * query.cell(r, s);
      norm_c[static_cast<std::size_t>(s)] += static_cast<double>(candidate.cell(r, s)) * candidate.cell(r, s);
    }
  }
  for (auto& n : norm_q) n = std::sqrt(n);
  for (auto& n : norm_c) n = std::sqrt(n);

  ScanContextMatch best;
  for (int shift = 0; shift < sectors; ++shift) {
    double sum = 0.0;
    int columns = 0;
    for (int s = 0; s < sectors; ++s) {
      const int t = (s + shift) % sectors;
      const double nq = norm_q[static_cast<std::size_t>(s)], nc = norm_c[static_cast<std::size_t>(t)];
      if (nq == 0.0 || nc == 0.0) continue;
      double dot = 0.0;
      for (int r = 0; r < rings; ++r) dot += static_cast<double>(query.cell(r, s)) * candidate.cell(r, t);
      sum += 1.0 - dot / (nq * nc);
      ++columns;
    }
    if (columns == 0) continue;
    const double distance = sum / columns;
    if (distance < best.distance) {
      best.distance = distance;
      best.sector_shift = shift;
    }
  }
  // shift k: query azimuth a sits where the candidate has a + k sectors
  const int signed_shift = best.sector_shift > sectors / 2 ? best.sector_shift - sectors : best.sector_shift;
  best.yaw = signed_shift * 2.0 * M_PI / sectors;
  return best;
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
  for (std::size_t k = 0; k < keep; ++k) {
    const Entry& e = entries_[by_key[k].second];
    out.push_back(Candidate{e.id, compare(context, e.context)});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Candidate& a, const Candidate& b) { return a.match.distance < b.match.distance; });
  return out;
}

}  // namespace rgbl
