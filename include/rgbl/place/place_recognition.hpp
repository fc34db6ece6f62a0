#pragma once
// Place recognition for loop closing behind one small interface: a recogniser remembers keyframes
// (by id) and, asked with a new one, names the remembered ones that look like the same place. Loop
// closing fuses the candidates of several recognisers and verifies each geometrically, so a
// recogniser only has to rank well, not decide. Built in, created by name:
//   - "scan_context": the keyframe's LiDAR scan (no training, invariant to heading);
//   - "bow": a bag of binary words over the keyframe's ORB descriptors (any depth source).
// Your own: implement PlaceRecognizer and hand it to LoopCloser::add_place_recognizer.

#include "rgbl/features/types.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/place/scan_context.hpp"
#include "rgbl/place/vocabulary.hpp"

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace rgbl {

// What a recogniser sees of a keyframe.
struct PlaceQuery {
  std::size_t id = 0;
  PointCloudView scan;                      // may be empty (a depth source without LiDAR)
  std::span<const Descriptor> descriptors;  // the keyframe's ORB descriptors
  // Keyframes covisible with it (remembered or not): what the same place looks like from nearby,
  // the bar a loop candidate must clear for a recogniser that scores relative to it.
  std::span<const std::size_t> neighbours;
};

struct PlaceCandidate {
  std::size_t id = 0;
  double similarity = 0.0;   // the recogniser's own score in [0, 1], 1 = identical; ranks its candidates
  std::string_view source;   // the recogniser's name
};

// A recogniser is used from one thread at a time (the loop closer's).
class PlaceRecognizer {
 public:
  virtual ~PlaceRecognizer() = default;
  virtual std::string_view name() const = 0;
  // At most `max` remembered places that look like the query, best first, among those `allowed`
  // accepts (a recent or covisible keyframe is not a loop). Does not remember the query.
  virtual std::vector<PlaceCandidate> query(const PlaceQuery& query, const std::function<bool(std::size_t)>& allowed,
                                            std::size_t max) const = 0;
  // Remembers the keyframe (a recogniser that cannot use it, e.g. no scan, ignores it).
  virtual void add(const PlaceQuery& query) = 0;
};

struct ScanContextPlaceOptions {
  ScanContextOptions descriptor;
  // Scan Context distance (0 same, 1 unrelated) below which a place is a candidate. On real sequence 04
  // consecutive scans (1.35 m) score at most 0.20 and scans >= 25 frames (~34 m) apart at least 0.49;
  // the same scan turned by half a sector scores 0.175. Verification, not this bound, decides.
  double max_distance = 0.35;
  std::size_t ring_key_neighbours = 10;  // places compared in full per query

  void validate() const;
};

struct BowPlaceOptions {
  // Vocabulary file written by `rgbl vocab train`; empty: the one rgbl ships (shipped_vocabulary()).
  std::string vocabulary;
  // A candidate must share at least this fraction of the words the best candidate shares with the
  // query (ORB-SLAM: 0.8), and score at least as well as the query's least similar covisible keyframe
  // and at least min_score.
  double min_common_words_ratio = 0.8;
  double min_score = 0.01;

  void validate() const;
};

struct PlaceRecognitionOptions {
  // Recognisers by name; their candidates are fused (each one's best max_candidates are verified).
  std::vector<std::string> methods = {"scan_context", "bow"};
  ScanContextPlaceOptions scan_context;
  BowPlaceOptions bow;

  void validate() const;  // ConfigError naming loop_closing.places.<key>
};

// Built-in recogniser names, sorted.
std::vector<std::string> place_recognizer_names();
// Creates a built-in recogniser. Throws ConfigError("loop_closing.places") for an unknown name (the
// message lists the known ones) and ParseError for a vocabulary file that cannot be loaded.
std::unique_ptr<PlaceRecognizer> make_place_recognizer(std::string_view name, const PlaceRecognitionOptions& options);

class ScanContextPlaces final : public PlaceRecognizer {
 public:
  explicit ScanContextPlaces(ScanContextPlaceOptions options);
  std::string_view name() const override { return "scan_context"; }
  std::vector<PlaceCandidate> query(const PlaceQuery& query, const std::function<bool(std::size_t)>& allowed,
                                    std::size_t max) const override;
  void add(const PlaceQuery& query) override;

 private:
  ScanContextPlaceOptions options_;
  ScanContextDatabase database_;
  mutable std::optional<std::pair<std::size_t, ScanContext>> last_;  // the last query's, for add()
};

// Inverted index from word to the keyframes holding it: a query scores only keyframes sharing words.
class BowPlaces final : public PlaceRecognizer {
 public:
  BowPlaces(Vocabulary vocabulary, BowPlaceOptions options);
  std::string_view name() const override { return "bow"; }
  std::vector<PlaceCandidate> query(const PlaceQuery& query, const std::function<bool(std::size_t)>& allowed,
                                    std::size_t max) const override;
  void add(const PlaceQuery& query) override;
  const Vocabulary& vocabulary() const { return vocabulary_; }

 private:
  Vocabulary vocabulary_;
  BowPlaceOptions options_;
  std::vector<std::size_t> ids_;                        // slot -> keyframe id
  std::vector<BowVector> vectors_;                      // slot -> its words
  std::unordered_map<std::size_t, std::size_t> slot_;   // keyframe id -> slot
  std::vector<std::vector<std::uint32_t>> inverted_;    // word -> slots holding it, ascending
  mutable std::optional<std::pair<std::size_t, BowVector>> last_;  // the last query's, for add()
  const BowVector& words_of(const PlaceQuery& query) const;
};

}  // namespace rgbl
