#include "rgbl/place/place_recognition.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/place/vocabulary.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/features/orb.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace {

rgbl::Descriptor random_descriptor(std::mt19937& rng) {
  rgbl::Descriptor d{};
  for (auto& byte : d) byte = static_cast<std::uint8_t>(rng() & 0xFFU);
  return d;
}

// `d` with `bits` distinct bits flipped.
rgbl::Descriptor flipped(rgbl::Descriptor d, int bits, std::mt19937& rng) {
  std::vector<int> order(256);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  for (int i = 0; i < bits; ++i) {
    const auto bit = static_cast<std::size_t>(order[static_cast<std::size_t>(i)]);
    d[bit / 8] = static_cast<std::uint8_t>(d[bit / 8] ^ (1U << (bit % 8)));
  }
  return d;
}

// Three well-separated clusters (random centres are ~128 bits apart; members 6 bits from theirs):
// cluster 0 in all 4 images, cluster 1 in images 0 and 1, cluster 2 in image 0 only.
struct Clusters {
  std::vector<rgbl::Descriptor> centres;
  std::vector<std::vector<rgbl::Descriptor>> images;
};
Clusters three_clusters() {
  std::mt19937 rng(7);
  Clusters c;
  for (int i = 0; i < 3; ++i) c.centres.push_back(random_descriptor(rng));
  c.images.resize(4);
  for (int image = 0; image < 4; ++image) {
    for (int cluster = 0; cluster < 3; ++cluster) {
      const int in_images = cluster == 0 ? 4 : cluster == 1 ? 2 : 1;
      if (image >= in_images) continue;
      for (int k = 0; k < 20; ++k) c.images[static_cast<std::size_t>(image)].push_back(flipped(c.centres[static_cast<std::size_t>(cluster)], 6, rng));
    }
  }
  return c;
}

std::vector<rgbl::Descriptor> describe(const std::filesystem::path& image) {
  rgbl::OrbExtractor extractor;
  std::vector<rgbl::Keypoint> keypoints;
  std::vector<rgbl::Descriptor> descriptors;
  const cv::Mat gray = rgbl::read_image_file(image, rgbl::ImageMode::grey);
  REQUIRE(!gray.empty());
  extractor.extract(gray, keypoints, descriptors);
  return descriptors;
}

rgbl::PlaceQuery query_of(std::size_t id, const std::vector<rgbl::Descriptor>& descriptors,
                          std::span<const std::size_t> neighbours = {}) {
  rgbl::PlaceQuery q;
  q.id = id;
  q.descriptors = descriptors;
  q.neighbours = neighbours;
  return q;
}

std::filesystem::path image04(int frame) {
  char name[16];
  std::snprintf(name, sizeof(name), "%06d.png", frame);
  return *rgbl::test::kitti_seq04() / "image_0" / name;
}

}  // namespace

TEST_CASE("vocabulary training finds separated clusters and weights words by inverse document frequency") {
  const Clusters c = three_clusters();
  const rgbl::Vocabulary v = rgbl::Vocabulary::train(c.images, {.branching = 3, .levels = 1});
  REQUIRE(v.words() == 3);
  REQUIRE(v.nodes() == 4);
  // every member of a cluster falls in one word, a different word per cluster
  std::vector<std::uint32_t> word_of(3);
  for (std::size_t k = 0; k < 3; ++k) word_of[k] = v.word(c.centres[k]);
  CHECK(word_of[0] != word_of[1]);
  CHECK(word_of[1] != word_of[2]);
  CHECK(word_of[0] != word_of[2]);
  std::mt19937 rng(11);
  for (std::size_t k = 0; k < 3; ++k) {
    for (int i = 0; i < 10; ++i) CHECK(v.word(flipped(c.centres[k], 10, rng)) == word_of[k]);
  }
  // idf = log(4 images / images holding the word)
  CHECK(v.weight(word_of[0]) == Approx(0.0).margin(1e-7));
  CHECK(v.weight(word_of[1]) == Approx(std::log(2.0)));
  CHECK(v.weight(word_of[2]) == Approx(std::log(4.0)));
  // image 0: 20 of each word, tf-idf 20 * (0, log 2, log 4), normalised: (1/3, 2/3) on words 1 and 2
  const rgbl::BowVector bow = v.transform(c.images[0]);
  REQUIRE(bow.size() == 2);  // word 0 weighs nothing
  for (const auto& [word, weight] : bow) {
    CHECK(weight == Approx(word == word_of[1] ? 1.0 / 3.0 : 2.0 / 3.0));
  }
  CHECK(rgbl::bow_similarity(bow, bow) == Approx(1.0));
  // image 2 holds word 0 only, which weighs 0: an empty vector, similar to nothing
  CHECK(v.transform(c.images[2]).empty());
  CHECK(rgbl::bow_similarity(v.transform(c.images[1]), bow) == Approx(1.0 / 3.0));
}

TEST_CASE("vocabulary training is deterministic and its file round-trips exactly") {
  const Clusters c = three_clusters();
  const rgbl::VocabularyOptions options{.branching = 2, .levels = 3};
  const rgbl::Vocabulary a = rgbl::Vocabulary::train(c.images, options);
  const rgbl::Vocabulary b = rgbl::Vocabulary::train(c.images, options);
  CHECK(a == b);
  CHECK(a.to_bytes() == b.to_bytes());
  CHECK(a.levels() == 3);
  CHECK(a.words() >= 3);
  const auto file = std::filesystem::temp_directory_path() / "rgbl_test_vocabulary.rgblvoc";
  a.save(file);
  CHECK(rgbl::Vocabulary::load(file) == a);
  std::filesystem::remove(file);
  // every descriptor still falls in the same word after the round trip
  const rgbl::Vocabulary back = rgbl::Vocabulary::from_bytes(a.to_bytes(), "memory");
  for (const auto& image : c.images) {
    for (const auto& d : image) CHECK(back.word(d) == a.word(d));
  }
}

TEST_CASE("a damaged vocabulary file is refused, naming the file and what is wrong") {
  const rgbl::Vocabulary v = rgbl::Vocabulary::train(three_clusters().images, {.branching = 3, .levels = 2});
  const std::vector<std::uint8_t> good = v.to_bytes();
  const auto refused = [](std::vector<std::uint8_t> bytes, const char* what) {
    CHECK_THROWS_MATCHES(rgbl::Vocabulary::from_bytes(bytes, "voc.bin"), rgbl::ParseError,
                         Catch::Matchers::Predicate<rgbl::ParseError>([&](const rgbl::ParseError& e) {
                           const std::string m = e.what();
                           return m.find("voc.bin") != std::string::npos && m.find(what) != std::string::npos;
                         }));
  };
  refused({}, "header");
  auto bad_magic = good;
  bad_magic[0] = 'X';
  refused(bad_magic, "header");
  refused(std::vector<std::uint8_t>(good.begin(), good.end() - 9), "truncated");
  auto damaged = good;
  damaged[40] ^= 0x10U;
  refused(damaged, "checksum");
  CHECK_THROWS_WITH(rgbl::Vocabulary::load("/nonexistent/voc.rgblvoc"),
                    Catch::Contains("/nonexistent/voc.rgblvoc") && Catch::Contains("missing"));
  CHECK_THROWS_WITH(rgbl::Vocabulary::train({}, {}), Catch::Contains("vocabulary.images"));
  CHECK_THROWS_WITH(rgbl::VocabularyOptions{.branching = 1}.validate(), Catch::Contains("vocabulary.branching"));
  CHECK_THROWS_WITH(rgbl::VocabularyOptions{.levels = 0}.validate(), Catch::Contains("vocabulary.levels"));
  CHECK_THROWS_WITH((rgbl::VocabularyOptions{.branching = 64, .levels = 8}.validate()),
                    Catch::Contains("vocabulary.levels"));
}

TEST_CASE("the shipped vocabulary is intact and recognises the same place on a real drive") {
  const rgbl::Vocabulary v = rgbl::shipped_vocabulary();
  CHECK(v.branching() == 10);
  CHECK(v.levels() == 4);
  CHECK(v.words() > 9000);
  if (!rgbl::test::kitti_seq04()) return;
  // every place that shares a word ranked (no common-word cut), and with the defaults
  rgbl::BowPlaceOptions every;
  every.min_common_words_ratio = 0.0;
  every.min_score = 0.0;
  rgbl::BowPlaces ranked(rgbl::shipped_vocabulary(), every);
  rgbl::BowPlaces places(rgbl::shipped_vocabulary(), {});
  std::vector<std::vector<rgbl::Descriptor>> kept;
  for (int f = 0; f <= 50; f += 5) {
    kept.push_back(describe(image04(f)));
    ranked.add(query_of(static_cast<std::size_t>(f), kept.back()));
    places.add(query_of(static_cast<std::size_t>(f), kept.back()));
  }
  const std::vector<rgbl::Descriptor> query = describe(image04(31));  // 1.35 m past frame 30
  const auto all = ranked.query(query_of(100, query), {}, 11);
  REQUIRE(all.size() == 11);
  CHECK(all.front().id == 30);
  CHECK(all.front().source == "bow");
  for (std::size_t i = 1; i < all.size(); ++i) CHECK(all[i - 1].similarity >= all[i].similarity);
  WARN("frame 31 against frames 0..50 step 5: frame " << all[0].id << " " << all[0].similarity << ", then frame "
       << all[1].id << " " << all[1].similarity << ", last frame " << all.back().id << " " << all.back().similarity);
  // measured: frame 30 0.34, frame 35 (5 frames on) 0.24, frame 0 (31 frames back) 0.14
  CHECK(all[0].similarity > 1.2 * all[1].similarity);
  CHECK(all.back().similarity < 0.5 * all[0].similarity);
  // the defaults keep places sharing >= 80 % of the best one's words: only frame 30
  const auto kept_by_default = places.query(query_of(100, query), {}, 11);
  REQUIRE(kept_by_default.size() == 1);
  CHECK(kept_by_default.front().id == 30);
  CHECK(kept_by_default.front().similarity == Approx(all.front().similarity));
  // a filter keeps frame 30 out
  for (const auto& c : ranked.query(query_of(100, query), [](std::size_t id) { return id != 30; }, 11)) {
    CHECK(c.id != 30);
  }
  // covisible keyframes set the bar: with frame 30 a neighbour of the query (as it is of frame 31),
  // every other place looks less like it than frame 30 does, so there is no candidate
  const std::vector<std::size_t> neighbours = {30};
  CHECK(ranked.query(query_of(100, query, neighbours), [](std::size_t id) { return id != 30; }, 11).empty());
}

TEST_CASE("place recognisers are created by name, and options are checked naming the field") {
  CHECK(rgbl::place_recognizer_names() == std::vector<std::string>{"bow", "scan_context"});
  rgbl::PlaceRecognitionOptions options;
  CHECK_NOTHROW(options.validate());
  CHECK(rgbl::make_place_recognizer("scan_context", options)->name() == "scan_context");
  CHECK(rgbl::make_place_recognizer("bow", options)->name() == "bow");
  CHECK_THROWS_WITH(rgbl::make_place_recognizer("netvlad", options),
                    Catch::Contains("loop_closing.places") && Catch::Contains("bow, scan_context") &&
                        Catch::Contains("netvlad"));
  options.bow.vocabulary = "/nonexistent/voc.rgblvoc";
  CHECK_THROWS_AS(rgbl::make_place_recognizer("bow", options), rgbl::ParseError);
  options = {};
  options.bow.min_common_words_ratio = 1.5;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("loop_closing.places.bow.min_common_words_ratio"));
  options = {};
  options.scan_context.ring_key_neighbours = 0;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("loop_closing.places.scan_context.ring_key_neighbours"));
}
