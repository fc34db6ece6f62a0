#include "rgbl/place/vocabulary.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>

namespace rgbl {

double bow_similarity(const BowVector& a, const BowVector& b) {
  // For L1-normalised positive vectors, 1 - |a - b|_1 / 2 is the sum over shared words of min(a, b).
  double score = 0.0;
  auto i = a.begin();
  auto j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->first < j->first) {
      ++i;
    } else if (j->first < i->first) {
      ++j;
    } else {
      score += std::min(i->second, j->second);
      ++i;
      ++j;
    }
  }
  return std::clamp(score, 0.0, 1.0);
}

void VocabularyOptions::validate() const {
  require(branching >= 2 && branching <= 64, "vocabulary.branching", "2..64 children per node");
  require(levels >= 1 && levels <= 8, "vocabulary.levels", "1..8 levels");
  require(std::pow(static_cast<double>(branching), levels) <= 16.0e6, "vocabulary.levels",
          "branching^levels <= 16 million words");
  require(iterations >= 1, "vocabulary.iterations", ">= 1 k-medians round");
}

namespace {

// Bitwise majority of the descriptors: the binary median (a tie gives 0).
Descriptor majority(const std::vector<Descriptor>& all, std::span<const std::uint32_t> members) {
  std::array<std::uint32_t, 256> ones{};
  for (const std::uint32_t m : members) {
    const Descriptor& d = all[m];
    for (std::size_t bit = 0; bit < 256; ++bit) ones[bit] += (d[bit / 8] >> (bit % 8)) & 1U;
  }
  Descriptor centre{};
  for (std::size_t bit = 0; bit < 256; ++bit) {
    if (2 * ones[bit] > members.size()) centre[bit / 8] = static_cast<std::uint8_t>(centre[bit / 8] | (1U << (bit % 8)));
  }
  return centre;
}

// Index in [0, count) of the centre nearest to d by Hamming distance (ties: the first).
template <class Centre>
std::size_t nearest_centre(const Descriptor& d, std::size_t count, Centre centre) {
  std::size_t best = 0;
  int best_distance = std::numeric_limits<int>::max();
  for (std::size_t c = 0; c < count; ++c) {
    const int distance = hamming_distance(d, centre(c));
    if (distance < best_distance) {
      best_distance = distance;
      best = c;
    }
  }
  return best;
}

// Uniform in [0, 1) from 53 bits: the same on every platform (std::uniform_real_distribution is not).
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// k-medians on `members` (indices into all), seeded by k-means++: the clusters, none empty, in the order
// of their seeds.
std::vector<std::vector<std::uint32_t>> cluster(const std::vector<Descriptor>& all,
                                                std::span<const std::uint32_t> members, int k, int iterations,
                                                std::mt19937_64& rng) {
  std::vector<Descriptor> centres;
  centres.push_back(all[members[static_cast<std::size_t>(rng() % members.size())]]);
  std::vector<double> nearest(members.size(), std::numeric_limits<double>::max());
  while (std::cmp_less(centres.size(), k)) {
    double total = 0.0;
    for (std::size_t i = 0; i < members.size(); ++i) {
      const double d = hamming_distance(all[members[i]], centres.back());
      nearest[i] = std::min(nearest[i], d * d);
      total += nearest[i];
    }
    if (total == 0.0) break;  // fewer distinct descriptors than k
    const double target = uniform(rng) * total;
    double sum = 0.0;
    std::size_t chosen = members.size() - 1;
    for (std::size_t i = 0; i < members.size(); ++i) {
      sum += nearest[i];
      if (sum > target && nearest[i] > 0.0) {
        chosen = i;
        break;
      }
    }
    centres.push_back(all[members[chosen]]);
  }
  std::vector<std::vector<std::uint32_t>> clusters;
  for (int round = 0; round < iterations; ++round) {
    std::vector<std::vector<std::uint32_t>> assigned(centres.size());
    for (const std::uint32_t m : members) {
      assigned[nearest_centre(all[m], centres.size(), [&](std::size_t c) -> const Descriptor& { return centres[c]; })]
          .push_back(m);
    }
    std::erase_if(assigned, [](const auto& c) { return c.empty(); });
    if (assigned == clusters) break;  // converged
    clusters = std::move(assigned);
    centres.clear();
    for (const auto& c : clusters) centres.push_back(majority(all, c));
  }
  return clusters;
}

// Little-endian fields of the file format.
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
std::uint64_t fnv1a(std::span<const std::uint8_t> bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const std::uint8_t b : bytes) {
    h ^= b;
    h *= 0x100000001b3ULL;
  }
  return h;
}

constexpr std::array<char, 8> kMagic = {'R', 'G', 'B', 'L', 'V', 'O', 'C', '1'};
constexpr std::size_t kHeaderBytes = 8 + 4 * 4;
constexpr std::size_t kNodeBytes = 32 + 4 + 4;  // centre, children, weight

}  // namespace

Vocabulary Vocabulary::train(std::span<const std::vector<Descriptor>> images, const VocabularyOptions& options) {
  options.validate();
  require(images.size() >= 2, "vocabulary.images", ">= 2 training images");
  std::vector<Descriptor> all;
  std::vector<std::uint32_t> image_of;  // descriptor -> image
  for (std::size_t i = 0; i < images.size(); ++i) {
    all.insert(all.end(), images[i].begin(), images[i].end());
    image_of.insert(image_of.end(), images[i].size(), static_cast<std::uint32_t>(i));
  }
  require(!all.empty(), "vocabulary.images", "images with at least one descriptor");
  require(all.size() < std::numeric_limits<std::uint32_t>::max(), "vocabulary.images", "< 4 billion descriptors");

  Vocabulary v;
  v.branching_ = options.branching;
  v.levels_ = options.levels;
  std::vector<std::vector<std::uint32_t>> members(1);  // per node, until it is split
  members[0].resize(all.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) members[0][i] = i;
  v.nodes_.push_back({.centre = Descriptor{}});
  std::vector<int> depth = {0};
  std::mt19937_64 rng(options.seed);
  // Breadth first: node n's children are appended together, so they are contiguous and after n.
  for (std::size_t n = 0; n < v.nodes_.size(); ++n) {
    if (depth[n] == options.levels || members[n].size() <= 1) continue;  // a leaf
    std::vector<std::vector<std::uint32_t>> parts;
    if (std::cmp_less_equal(members[n].size(), options.branching)) {
      for (const std::uint32_t m : members[n]) parts.push_back({m});  // each descriptor its own word
    } else {
      parts = cluster(all, members[n], options.branching, options.iterations, rng);
    }
    if (parts.size() <= 1) continue;  // all alike: a leaf
    v.nodes_[n].first_child = static_cast<std::uint32_t>(v.nodes_.size());
    v.nodes_[n].children = static_cast<std::uint32_t>(parts.size());
    for (auto& part : parts) {
      v.nodes_.push_back({.centre = majority(all, part)});
      depth.push_back(depth[n] + 1);
      members.push_back(std::move(part));
    }
    members[n] = {};
    members[n].shrink_to_fit();
  }
  // Words are the leaves in node order; weight = log(N / images holding the word).
  for (std::size_t n = 0; n < v.nodes_.size(); ++n) {
    if (v.nodes_[n].children != 0) continue;
    v.nodes_[n].word = static_cast<std::uint32_t>(v.leaves_.size());
    v.leaves_.push_back(static_cast<std::uint32_t>(n));
    std::vector<std::uint32_t> holding;  // images, each once
    for (const std::uint32_t m : members[n]) holding.push_back(image_of[m]);
    std::sort(holding.begin(), holding.end());
    const auto count = std::distance(holding.begin(), std::unique(holding.begin(), holding.end()));
    v.nodes_[n].weight = static_cast<float>(std::log(static_cast<double>(images.size()) / std::max<std::ptrdiff_t>(count, 1)));
  }
  return v;
}

std::uint32_t Vocabulary::word(const Descriptor& descriptor) const {
  std::uint32_t n = 0;
  while (nodes_[n].children != 0) {
    const std::uint32_t first = nodes_[n].first_child;
    n = first + static_cast<std::uint32_t>(nearest_centre(descriptor, nodes_[n].children, [&](std::size_t c) -> const Descriptor& {
          return nodes_[first + c].centre;
        }));
  }
  return nodes_[n].word;
}

float Vocabulary::weight(std::uint32_t word) const { return nodes_[leaves_.at(word)].weight; }

BowVector Vocabulary::transform(std::span<const Descriptor> descriptors) const {
  BowVector v;
  if (empty() || descriptors.empty()) return v;
  std::vector<std::uint32_t> words;
  words.reserve(descriptors.size());
  for (const Descriptor& d : descriptors) words.push_back(word(d));
  std::sort(words.begin(), words.end());
  double total = 0.0;
  for (std::size_t i = 0; i < words.size();) {
    std::size_t j = i;
    while (j < words.size() && words[j] == words[i]) ++j;
    const double w = static_cast<double>(j - i) * weight(words[i]);  // tf (unnormalised) x idf
    if (w > 0.0) {
      v.emplace_back(words[i], static_cast<float>(w));
      total += w;
    }
    i = j;
  }
  for (auto& [word, w] : v) w = static_cast<float>(w / total);
  std::erase_if(v, [](const auto& e) { return !(e.second > 0.0F); });  // underflow: a word far lighter than the rest
  return v;
}

std::vector<std::uint8_t> Vocabulary::to_bytes() const {
  std::vector<std::uint8_t> out(kMagic.begin(), kMagic.end());
  put_u32(out, static_cast<std::uint32_t>(branching_));
  put_u32(out, static_cast<std::uint32_t>(levels_));
  put_u32(out, static_cast<std::uint32_t>(nodes_.size()));
  put_u32(out, static_cast<std::uint32_t>(leaves_.size()));
  out.reserve(out.size() + nodes_.size() * kNodeBytes + 8);
  for (const Node& n : nodes_) {
    out.insert(out.end(), n.centre.begin(), n.centre.end());
    put_u32(out, n.children);
    std::uint32_t bits = 0;
    std::memcpy(&bits, &n.weight, 4);
    put_u32(out, bits);
  }
  const std::uint64_t check = fnv1a(out);
  put_u32(out, static_cast<std::uint32_t>(check));
  put_u32(out, static_cast<std::uint32_t>(check >> 32));
  return out;
}

Vocabulary Vocabulary::from_bytes(std::span<const std::uint8_t> bytes, const std::filesystem::path& name) {
  const auto fail = [&](const std::string& what) {
    throw ParseError(name, 0, fmt::format("not an rgbl vocabulary ({}): expected a file written by `rgbl vocab "
                                          "train` (format {})",
                                          what, std::string(kMagic.begin(), kMagic.end())));
  };
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(bytes[at + static_cast<std::size_t>(i)]) << (8 * i);
    return v;
  };
  if (bytes.size() < kHeaderBytes + 8 || !std::equal(kMagic.begin(), kMagic.end(), bytes.begin())) {
    fail("no RGBLVOC1 header");
  }
  const std::uint32_t branching = u32(8), levels = u32(12), nodes = u32(16), words = u32(20);
  if (bytes.size() != kHeaderBytes + static_cast<std::size_t>(nodes) * kNodeBytes + 8) {
    fail(fmt::format("{} bytes for {} nodes: truncated or padded", bytes.size(), nodes));
  }
  const std::size_t body = bytes.size() - 8;
  if (fnv1a(bytes.first(body)) != (static_cast<std::uint64_t>(u32(body + 4)) << 32 | u32(body))) {
    fail("checksum mismatch: the file is damaged");
  }
  try {
    VocabularyOptions{.branching = static_cast<int>(std::min<std::uint32_t>(branching, 1000)),
                      .levels = static_cast<int>(std::min<std::uint32_t>(levels, 1000))}
        .validate();
  } catch (const ConfigError& e) {
    fail(e.what());
  }
  if (nodes == 0) fail("no nodes");
  Vocabulary v;
  v.branching_ = static_cast<int>(branching);
  v.levels_ = static_cast<int>(levels);
  v.nodes_.resize(nodes);
  std::uint32_t next_child = 1;  // breadth first: children follow in order
  for (std::uint32_t n = 0; n < nodes; ++n) {
    const std::size_t at = kHeaderBytes + static_cast<std::size_t>(n) * kNodeBytes;
    Node& node = v.nodes_[n];
    std::copy_n(bytes.begin() + static_cast<std::ptrdiff_t>(at), 32, node.centre.begin());
    node.children = u32(at + 32);
    const std::uint32_t bits = u32(at + 36);
    std::memcpy(&node.weight, &bits, 4);
    if (node.children > branching || node.children == 1 || nodes - next_child < node.children) {
      fail(fmt::format("node {} has {} children", n, node.children));
    }
    if (node.children != 0) {
      node.first_child = next_child;
      next_child += node.children;
      node.weight = 0.0F;
    } else {
      // an idf is log(images / images holding the word): >= 0, and below 100 for any training set
      if (!(node.weight >= 0.0F && node.weight < 100.0F)) fail(fmt::format("node {} has weight {}", n, node.weight));
      node.word = static_cast<std::uint32_t>(v.leaves_.size());
      v.leaves_.push_back(n);
    }
  }
  if (next_child != nodes) fail("nodes no parent reaches");
  if (v.leaves_.size() != words) fail(fmt::format("{} words in the header, {} leaves", words, v.leaves_.size()));
  // Depth bounded by levels: every child comes after its parent, so one pass finds each node's depth.
  std::vector<std::uint32_t> depth(nodes, 0);
  for (std::uint32_t n = 0; n < nodes; ++n) {
    for (std::uint32_t c = 0; c < v.nodes_[n].children; ++c) depth[v.nodes_[n].first_child + c] = depth[n] + 1;
    if (depth[n] > levels) fail(fmt::format("node {} at depth {} of {} levels", n, depth[n], levels));
  }
  return v;
}

Vocabulary Vocabulary::load(const std::filesystem::path& file) {
  std::ifstream in = open_input_file(file, "a vocabulary written by `rgbl vocab train`", true);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw ParseError(file, 0, "read error (expected a vocabulary)");
  return from_bytes(bytes, file);
}

void Vocabulary::save(const std::filesystem::path& file) const {
  const std::vector<std::uint8_t> bytes = to_bytes();
  write_atomically(file, [&](std::ofstream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  });
}

}  // namespace rgbl
