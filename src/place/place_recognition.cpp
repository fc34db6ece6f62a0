#include "rgbl/place/place_recognition.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <set>

namespace rgbl {

void ScanContextPlaceOptions::validate() const {
  descriptor.validate();
  require(max_distance > 0.0 && max_distance <= 1.0, "loop_closing.places.scan_context.max_distance",
          "a Scan Context distance in (0, 1]");
  require(ring_key_neighbours >= 1, "loop_closing.places.scan_context.ring_key_neighbours", ">= 1 place");
}

void BowPlaceOptions::validate() const {
  require(min_common_words_ratio >= 0.0 && min_common_words_ratio <= 1.0,
          "loop_closing.places.bow.min_common_words_ratio", "a fraction in [0, 1]");
  require(min_score >= 0.0 && min_score < 1.0, "loop_closing.places.bow.min_score", "a score in [0, 1)");
}

void PlaceRecognitionOptions::validate() const {
  const std::vector<std::string> known = place_recognizer_names();
  std::set<std::string> seen;
  for (const std::string& m : methods) {
    if (std::find(known.begin(), known.end(), m) == known.end()) {
      throw ConfigError("loop_closing.places",
                        fmt::format("known place recognisers ({}), not '{}'", fmt::join(known, ", "), m));
    }
    if (!seen.insert(m).second) throw ConfigError("loop_closing.places", fmt::format("'{}' once, not twice", m));
  }
  scan_context.validate();
  bow.validate();
}

std::vector<std::string> place_recognizer_names() { return {"bow", "scan_context"}; }

std::unique_ptr<PlaceRecognizer> make_place_recognizer(std::string_view name, const PlaceRecognitionOptions& options) {
  if (name == "scan_context") return std::make_unique<ScanContextPlaces>(options.scan_context);
  if (name == "bow") {
    return std::make_unique<BowPlaces>(
        options.bow.vocabulary.empty() ? shipped_vocabulary() : Vocabulary::load(options.bow.vocabulary),
        options.bow);
  }
  throw ConfigError("loop_closing.places", fmt::format("known place recognisers ({}), not '{}'",
                                                       fmt::join(place_recognizer_names(), ", "), name));
}

ScanContextPlaces::ScanContextPlaces(ScanContextPlaceOptions options) : options_(std::move(options)) {
  options_.validate();
}

std::vector<PlaceCandidate> ScanContextPlaces::query(const PlaceQuery& query,
                                                     const std::function<bool(std::size_t)>& allowed,
                                                     std::size_t max) const {
  std::vector<PlaceCandidate> out;
  if (query.scan.empty()) return out;
  last_.emplace(query.id, make_scan_context(query.scan, options_.descriptor));
  for (const auto& place : database_.query(last_->second, options_.ring_key_neighbours, allowed)) {
    if (place.match.distance > options_.max_distance || out.size() >= max) break;  // sorted, best first
    out.push_back({place.id, 1.0 - place.match.distance, name()});
  }
  return out;
}

void ScanContextPlaces::add(const PlaceQuery& query) {
  if (query.scan.empty()) return;
  if (!last_ || last_->first != query.id) last_.emplace(query.id, make_scan_context(query.scan, options_.descriptor));
  database_.add(query.id, std::move(last_->second));
  last_.reset();
}

BowPlaces::BowPlaces(Vocabulary vocabulary, BowPlaceOptions options)
    : vocabulary_(std::move(vocabulary)), options_(std::move(options)) {
  options_.validate();
  if (vocabulary_.empty()) throw ConfigError("loop_closing.places.bow.vocabulary", "a vocabulary with words");
  inverted_.resize(vocabulary_.words());
}

const BowVector& BowPlaces::words_of(const PlaceQuery& query) const {
  if (!last_ || last_->first != query.id) last_.emplace(query.id, vocabulary_.transform(query.descriptors));
  return last_->second;
}

std::vector<PlaceCandidate> BowPlaces::query(const PlaceQuery& query, const std::function<bool(std::size_t)>& allowed,
                                             std::size_t max) const {
  std::vector<PlaceCandidate> out;
  const BowVector& words = words_of(query);
  if (words.empty() || ids_.empty()) return out;
  // The bar: how similar the place looks from the keyframes that see it too (ORB-SLAM's minimum score).
  double bar = options_.min_score;
  double least_neighbour = 1.0;
  bool any_neighbour = false;
  for (const std::size_t n : query.neighbours) {
    const auto slot = slot_.find(n);
    if (slot == slot_.end()) continue;
    least_neighbour = std::min(least_neighbour, bow_similarity(words, vectors_[slot->second]));
    any_neighbour = true;
  }
  if (any_neighbour) bar = std::max(bar, least_neighbour);
  // Words shared with each allowed remembered keyframe, through the inverted index.
  std::vector<std::uint32_t> common(ids_.size(), 0);
  std::vector<char> checked(ids_.size(), 0);  // 1 allowed, 2 not
  std::uint32_t most = 0;
  for (const auto& [word, weight] : words) {
    for (const std::uint32_t slot : inverted_[word]) {
      if (checked[slot] == 0) checked[slot] = (!allowed || allowed(ids_[slot])) ? 1 : 2;
      if (checked[slot] != 1) continue;
      most = std::max(most, ++common[slot]);
    }
  }
  if (most == 0) return out;
  const double min_common = options_.min_common_words_ratio * most;
  for (std::size_t slot = 0; slot < ids_.size(); ++slot) {
    if (checked[slot] != 1 || common[slot] < min_common) continue;
    const double score = bow_similarity(words, vectors_[slot]);
    if (score >= bar) out.push_back({ids_[slot], score, name()});
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.similarity > b.similarity; });
  if (out.size() > max) out.resize(max);
  return out;
}

void BowPlaces::add(const PlaceQuery& query) {
  if (slot_.contains(query.id)) return;
  const auto slot = static_cast<std::uint32_t>(ids_.size());
  BowVector words = words_of(query);
  last_.reset();
  for (const auto& [word, weight] : words) inverted_[word].push_back(slot);
  ids_.push_back(query.id);
  vectors_.push_back(std::move(words));
  slot_.emplace(query.id, slot);
}

}  // namespace rgbl
