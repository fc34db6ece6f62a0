#pragma once
// A bag of binary words: a vocabulary tree over 256-bit ORB descriptors (hierarchical k-medians,
// Nister and Stewenius, CVPR 2006; binary words as in Galvez-Lopez and Tardos, T-RO 2012). An image
// becomes a sparse vector of word weights (term frequency x inverse document frequency, L1-normalised)
// and two images compare by the L1 score of their vectors. Loop closing finds candidate places with it
// when a keyframe has no LiDAR scan (stereo, RGB-D, precomputed depth) and beside Scan Context when it
// has one (docs/loop-closing.md).
//
// rgbl ships a default vocabulary (shipped_vocabulary(), embedded in the library) trained by
// `rgbl vocab train` on documented images; a vocabulary is a plain value, loaded and saved explicitly.

#include "rgbl/features/types.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace rgbl {

// Word id -> weight, sorted by word id, weights > 0 summing to 1 (empty: no descriptor had a word
// with weight).
using BowVector = std::vector<std::pair<std::uint32_t, float>>;

// L1 score of two BowVectors (DBoW2's): 1 - |a - b|_1 / 2, in [0, 1]; 1 = the same distribution of
// words, 0 = no word in common.
double bow_similarity(const BowVector& a, const BowVector& b);

struct VocabularyOptions {
  int branching = 10;   // children per node (k of k-medians)
  int levels = 4;       // depth of the tree: up to branching^levels words
  int iterations = 10;  // k-medians rounds per node (fewer when the assignment stops changing)
  std::uint64_t seed = 1;

  void validate() const;  // ConfigError naming vocabulary.<key>
};

class Vocabulary {
 public:
  Vocabulary() = default;

  // Trains on the descriptors of a set of images (one vector per image: the inverse document
  // frequency counts images). Deterministic for equal inputs and options. Throws ConfigError on bad
  // options or when there are fewer than 2 images or no descriptor.
  static Vocabulary train(std::span<const std::vector<Descriptor>> images, const VocabularyOptions& options = {});

  // Binary file (docs/loop-closing.md, "Vocabulary file"). load throws ParseError naming the file on
  // anything that is not a complete, intact vocabulary; save writes atomically and throws Error
  // naming the file when it cannot.
  static Vocabulary load(const std::filesystem::path& file);
  void save(const std::filesystem::path& file) const;
  // The same format from memory; `name` is what errors call the bytes.
  static Vocabulary from_bytes(std::span<const std::uint8_t> bytes, const std::filesystem::path& name);
  std::vector<std::uint8_t> to_bytes() const;

  bool empty() const { return nodes_.empty(); }
  std::size_t words() const { return leaves_.size(); }
  std::size_t nodes() const { return nodes_.size(); }
  int branching() const { return branching_; }
  int levels() const { return levels_; }
  // The word a descriptor falls into: the nearest child by Hamming distance at every level (ties: the
  // first child). Requires a non-empty vocabulary.
  std::uint32_t word(const Descriptor& descriptor) const;
  // Inverse document frequency of a word: log(training images / images holding it).
  float weight(std::uint32_t word) const;
  // An image's vector: words weighted by tf-idf, L1-normalised.
  BowVector transform(std::span<const Descriptor> descriptors) const;

  friend bool operator==(const Vocabulary&, const Vocabulary&) = default;

 private:
  struct Node {
    Descriptor centre{};
    std::uint32_t first_child = 0;  // children are contiguous; none for a leaf
    std::uint32_t children = 0;
    std::uint32_t word = 0;  // leaves only
    float weight = 0.0F;     // leaves only

    friend bool operator==(const Node&, const Node&) = default;
  };
  int branching_ = 0, levels_ = 0;
  std::vector<Node> nodes_;            // breadth first: node 0 is the root, parents before children
  std::vector<std::uint32_t> leaves_;  // word -> node
};

// The vocabulary rgbl ships (embedded in the library; how it was made: docs/loop-closing.md).
// Parsed on each call: keep the result.
Vocabulary shipped_vocabulary();

}  // namespace rgbl
