#include "rgbl/core/error.hpp"
#include "rgbl/features/matcher.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

namespace {

rgbl::Descriptor random_descriptor(std::mt19937& rng) {
  rgbl::Descriptor d{};
  for (auto& byte : d) byte = static_cast<std::uint8_t>(rng() & 0xFFU);
  return d;
}

// A copy of `d` with exactly `bits` distinct bits flipped.
rgbl::Descriptor flip_bits(const rgbl::Descriptor& d, int bits, std::mt19937& rng) {
  std::vector<int> positions(256);
  for (int i = 0; i < 256; ++i) positions[static_cast<std::size_t>(i)] = i;
  std::shuffle(positions.begin(), positions.end(), rng);
  rgbl::Descriptor out = d;
  for (int i = 0; i < bits; ++i) {
    const int p = positions[static_cast<std::size_t>(i)];
    out[static_cast<std::size_t>(p / 8)] ^= static_cast<std::uint8_t>(1U << (p % 8));
  }
  return out;
}

// Keypoints on a 40 px lattice over a 640x480 frame, all on level 0 with angle 10 degrees.
struct Frame {
  std::vector<rgbl::Keypoint> keypoints;
  std::vector<rgbl::Descriptor> descriptors;
};

Frame lattice_frame(std::mt19937& rng) {
  Frame f;
  for (int y = 20; y < 480; y += 40) {
    for (int x = 20; x < 640; x += 40) {
      rgbl::Keypoint k;
      k.x = static_cast<float>(x);
      k.y = static_cast<float>(y);
      k.angle = 10.0F;
      f.keypoints.push_back(k);
      f.descriptors.push_back(random_descriptor(rng));
    }
  }
  return f;
}

}  // namespace

TEST_CASE("hamming distance counts differing bits", "[features][matcher]") {
  std::mt19937 rng(1);
  const auto a = random_descriptor(rng);
  CHECK(rgbl::hamming_distance(a, a) == 0);
  for (int bits : {1, 7, 64, 200, 256}) CHECK(rgbl::hamming_distance(a, flip_bits(a, bits, rng)) == bits);
}

TEST_CASE("feature grid returns exactly the keypoints in the window and level range", "[features][matcher]") {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> ux(0.0F, 639.99F), uy(0.0F, 479.99F);
  std::vector<rgbl::Keypoint> kps(3000);
  for (auto& k : kps) {
    k.x = ux(rng);
    k.y = uy(rng);
    k.level = static_cast<int>(rng() % 8);
  }
  const rgbl::FeatureGrid grid(kps, 640, 480, 16);
  std::vector<int> out;
  for (int trial = 0; trial < 200; ++trial) {
    const float x = ux(rng), y = uy(rng), r = 3.0F + static_cast<float>(trial % 40);
    const int lo = static_cast<int>(rng() % 4), hi = trial % 3 == 0 ? -1 : lo + static_cast<int>(rng() % 4);
    grid.query(x, y, r, lo, hi, out);
    std::vector<int> expected;
    for (std::size_t i = 0; i < kps.size(); ++i) {
      const auto& k = kps[i];
      if (std::abs(k.x - x) <= r && std::abs(k.y - y) <= r && k.level >= lo && (hi < 0 || k.level <= hi)) {
        expected.push_back(static_cast<int>(i));
      }
    }
    std::sort(out.begin(), out.end());
    REQUIRE(out == expected);
  }
  // Outside the image: nothing, and `out` is cleared.
  grid.query(-100.0F, -100.0F, 10.0F, 0, -1, out);
  CHECK(out.empty());
  const rgbl::FeatureGrid empty;
  empty.query(10.0F, 10.0F, 50.0F, 0, -1, out);
  CHECK(out.empty());
}

TEST_CASE("guided matcher finds known correspondences and rejects far predictions", "[features][matcher]") {
  std::mt19937 rng(3);
  const Frame f = lattice_frame(rng);
  const rgbl::FeatureGrid grid(f.keypoints, 640, 480);
  std::vector<rgbl::Descriptor> query_desc;
  std::vector<rgbl::GuidedQuery> queries;
  for (std::size_t i = 0; i < f.keypoints.size(); ++i) query_desc.push_back(flip_bits(f.descriptors[i], 20, rng));
  std::normal_distribution<float> noise(0.0F, 3.0F);
  for (std::size_t i = 0; i < f.keypoints.size(); ++i) {
    rgbl::GuidedQuery q;
    q.x = f.keypoints[i].x + noise(rng);
    q.y = f.keypoints[i].y + noise(rng);
    q.angle = 10.0F;
    q.descriptor = &query_desc[i];
    queries.push_back(q);
  }
  // One query predicted 25 px off (outside the 15 px radius), one without descriptor.
  queries[5].x += 25.0F;
  queries[6].descriptor = nullptr;
  const rgbl::GuidedMatchOptions options;
  const auto result = rgbl::match_guided(queries, grid, f.keypoints, f.descriptors, options);
  REQUIRE(result.size() == queries.size());
  int correct = 0;
  for (std::size_t i = 0; i < result.size(); ++i) {
    if (i == 5 || i == 6) continue;
    correct += result[i] == static_cast<int>(i) ? 1 : 0;
  }
  CHECK(correct == static_cast<int>(queries.size()) - 2);
  CHECK(result[6] == -1);
  // 25 px right of keypoint 5 is 15 px from keypoint 6 (lattice step 40), whose descriptor is random:
  // Hamming ~128 > 100, so no match.
  CHECK(result[5] == -1);

  // The radius scales with the predicted level: at level 3 the radius is 15 * 1.2^3 = 25.9 px.
  auto far = queries[5];
  far.x = f.keypoints[5].x + 22.0F;
  far.y = f.keypoints[5].y;
  far.level = 3;
  std::vector<rgbl::Keypoint> leveled = f.keypoints;
  for (auto& k : leveled) k.level = 3;
  const rgbl::FeatureGrid grid3(leveled, 640, 480);
  const std::vector<rgbl::GuidedQuery> one{far};
  CHECK(rgbl::match_guided(one, grid3, leveled, f.descriptors, options)[0] == 5);
  // ... and the level window excludes level-0 keypoints for a level-3 prediction.
  CHECK(rgbl::match_guided(one, grid, f.keypoints, f.descriptors, options)[0] == -1);
}

TEST_CASE("guided matcher: ratio test, level rule, distance threshold, one match per keypoint",
          "[features][matcher]") {
  std::mt19937 rng(4);
  const auto base = random_descriptor(rng);
  std::vector<rgbl::Keypoint> kps(2);
  kps[0].x = 100.0F;
  kps[0].y = 100.0F;
  kps[1].x = 105.0F;
  kps[1].y = 100.0F;
  // Keypoint 0 at distance 10 from the query, keypoint 1 at distance 11: ambiguous.
  const auto query_desc = base;
  std::vector<rgbl::Descriptor> desc{flip_bits(base, 10, rng), flip_bits(base, 11, rng)};
  rgbl::GuidedQuery q;
  q.x = 101.0F;
  q.y = 100.0F;
  q.descriptor = &query_desc;
  const std::vector<rgbl::GuidedQuery> queries{q};
  rgbl::GuidedMatchOptions options;
  options.check_orientation = false;
  {
    const rgbl::FeatureGrid grid(kps, 200, 200);
    CHECK(rgbl::match_guided(queries, grid, kps, desc, options)[0] == -1);  // 10 >= 0.8 * 11
    options.ratio = 1.0F;
    CHECK(rgbl::match_guided(queries, grid, kps, desc, options)[0] == 0);  // ratio test off
    options.ratio = 0.8F;
  }
  {
    // The runner-up on another level does not count (ORB-SLAM's rule).
    kps[1].level = 1;
    const rgbl::FeatureGrid grid(kps, 200, 200);
    CHECK(rgbl::match_guided(queries, grid, kps, desc, options)[0] == 0);
    kps[1].level = 0;
  }
  {
    // A clear winner passes the ratio test: 10 < 0.8 * 40.
    desc[1] = flip_bits(base, 40, rng);
    const rgbl::FeatureGrid grid(kps, 200, 200);
    CHECK(rgbl::match_guided(queries, grid, kps, desc, options)[0] == 0);
    options.max_distance = 9;
    CHECK(rgbl::match_guided(queries, grid, kps, desc, options)[0] == -1);
    options.max_distance = 100;
  }
  {
    // Two queries want keypoint 0: the closer one in Hamming distance wins, whatever the order.
    const auto worse_desc = flip_bits(desc[0], 30, rng);
    rgbl::GuidedQuery worse = q;
    worse.descriptor = &worse_desc;
    const rgbl::FeatureGrid grid(kps, 200, 200);
    const std::vector<rgbl::GuidedQuery> a{worse, q}, b{q, worse};
    CHECK(rgbl::match_guided(a, grid, kps, desc, options) == std::vector<int>{-1, 0});
    CHECK(rgbl::match_guided(b, grid, kps, desc, options) == std::vector<int>{0, -1});
  }
}

TEST_CASE("guided matcher: rotation histogram keeps the dominant rotations", "[features][matcher]") {
  std::mt19937 rng(5);
  Frame f = lattice_frame(rng);  // 192 keypoints
  const rgbl::FeatureGrid grid(f.keypoints, 640, 480);
  std::vector<rgbl::Descriptor> query_desc;
  for (const auto& d : f.descriptors) query_desc.push_back(flip_bits(d, 15, rng));
  std::vector<rgbl::GuidedQuery> queries;
  for (std::size_t i = 0; i < f.keypoints.size(); ++i) {
    rgbl::GuidedQuery q;
    q.x = f.keypoints[i].x;
    q.y = f.keypoints[i].y;
    q.descriptor = &query_desc[i];
    // Most matches rotate by +40 deg, some by +52 (neighbour bins) and 8 by 200 deg (outliers).
    q.angle = f.keypoints[i].angle + (i % 24 == 0 ? 200.0F : (i % 5 == 0 ? 52.0F : 40.0F));
    queries.push_back(q);
  }
  rgbl::GuidedMatchOptions options;
  auto result = rgbl::match_guided(queries, grid, f.keypoints, f.descriptors, options);
  for (std::size_t i = 0; i < result.size(); ++i) {
    INFO("query " << i);
    CHECK(result[i] == (i % 24 == 0 ? -1 : static_cast<int>(i)));
  }
  // keep_bins = 1 keeps only the 40 deg bin.
  options.keep_bins = 1;
  result = rgbl::match_guided(queries, grid, f.keypoints, f.descriptors, options);
  for (std::size_t i = 0; i < result.size(); ++i) {
    const bool dominant = i % 24 != 0 && i % 5 != 0;
    CHECK(result[i] == (dominant ? static_cast<int>(i) : -1));
  }
  // Without the check every match survives.
  options.check_orientation = false;
  result = rgbl::match_guided(queries, grid, f.keypoints, f.descriptors, options);
  CHECK(std::count(result.begin(), result.end(), -1) == 0);
}

TEST_CASE("brute-force matcher: known permutation, ratio test, cross check", "[features][matcher]") {
  std::mt19937 rng(6);
  std::vector<rgbl::Descriptor> train;
  for (int i = 0; i < 500; ++i) train.push_back(random_descriptor(rng));
  std::vector<int> perm(train.size());
  for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = static_cast<int>(i);
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<rgbl::Descriptor> query;
  for (const int p : perm) query.push_back(flip_bits(train[static_cast<std::size_t>(p)], 25, rng));
  rgbl::BruteForceMatchOptions options;
  auto matches = rgbl::match_brute_force(query, train, options);
  REQUIRE(matches.size() == query.size());
  for (const auto& m : matches) {
    CHECK(m.train == perm[static_cast<std::size_t>(m.query)]);
    CHECK(m.distance == 25);
  }
  // A near-duplicate of train[perm[0]] makes query 0 ambiguous: 25 vs <= 30 fails 0.7.
  train.push_back(flip_bits(train[static_cast<std::size_t>(perm[0])], 5, rng));
  matches = rgbl::match_brute_force(query, train, options);
  CHECK(matches.size() == query.size() - 1);
  CHECK(std::none_of(matches.begin(), matches.end(), [](const rgbl::Match& m) { return m.query == 0; }));
  // Distance threshold.
  options.max_distance = 24;
  CHECK(rgbl::match_brute_force(query, train, options).empty());
  // Cross check: two queries share a nearest train descriptor; only the closer one survives.
  options = {};
  options.ratio = 1.0F;
  std::vector<rgbl::Descriptor> q2{flip_bits(train[0], 10, rng), flip_bits(train[0], 20, rng)};
  const std::vector<rgbl::Descriptor> t2{train[0], train[1]};
  CHECK(rgbl::match_brute_force(q2, t2, options).size() == 2);
  options.cross_check = true;
  matches = rgbl::match_brute_force(q2, t2, options);
  REQUIRE(matches.size() == 1);
  CHECK(matches[0].query == 0);
  CHECK(matches[0].train == 0);
  CHECK(matches[0].distance == 10);
  // The second-nearest distance, for a caller's own ratio test (INT_MAX: no second train descriptor).
  CHECK(matches[0].second_distance == rgbl::hamming_distance(q2[0], t2[1]));
  const std::vector<rgbl::Descriptor> t1{train[0]};
  matches = rgbl::match_brute_force(q2, t1, options);
  REQUIRE(matches.size() == 1);
  CHECK(matches[0].second_distance == std::numeric_limits<int>::max());
  CHECK(rgbl::match_brute_force({}, t2, options).empty());
}

TEST_CASE("rotation consistency keeps the fullest bins holding >= 10 % of the top one", "[features][matcher]") {
  // 30 bins of 12 deg centred on multiples of 12: 40 and -320 -> bin 3, 52 -> 4, 200 -> 17, 100 -> 8,
  // 359 -> 30, which wraps to 0.
  std::vector<float> rotations;
  for (int i = 0; i < 20; ++i) rotations.push_back(i % 2 == 0 ? 40.0F : -320.0F);
  for (int i = 0; i < 3; ++i) rotations.push_back(52.0F);
  for (int i = 0; i < 2; ++i) rotations.push_back(200.0F);  // exactly 10 % of the fullest
  rotations.push_back(100.0F);
  rotations.push_back(359.0F);
  std::vector<char> expected(rotations.size(), 1);
  expected[25] = expected[26] = 0;  // bins 8 and 0: not among the 3 fullest
  CHECK(rgbl::rotation_consistent(rotations, 30, 3) == expected);
  rotations.push_back(40.0F);  // the fullest bin grows to 21: bin 17 is below 10 %
  expected[23] = expected[24] = 0;
  expected.push_back(1);
  CHECK(rgbl::rotation_consistent(rotations, 30, 3) == expected);
  // keep_bins = 1: only the fullest bin; 359 deg is in bin 0 (wrapped), i.e. next to 0 deg.
  const std::vector<float> around_zero{359.0F, 1.0F, 5.9F, 6.1F};
  CHECK(rgbl::rotation_consistent(around_zero, 30, 1) == std::vector<char>{1, 1, 1, 0});
  CHECK(rgbl::rotation_consistent({}, 30, 3).empty());
  CHECK_THROWS_WITH(rgbl::rotation_consistent(around_zero, 30, 31), Catch::Contains("rotation_consistent.keep_bins"));
}

TEST_CASE("matcher options validation names the key", "[features][matcher]") {
  rgbl::GuidedMatchOptions g;
  CHECK_NOTHROW(g.validate());
  g.keep_bins = 31;
  CHECK_THROWS_AS(g.validate(), rgbl::ConfigError);
  g = {};
  g.ratio = 0.0F;
  try {
    g.validate();
    FAIL("expected ConfigError");
  } catch (const rgbl::ConfigError& e) {
    CHECK(e.key() == "guided_match.ratio");
  }
  g = {};
  g.scale_factor = 0.9F;
  CHECK_THROWS_AS(g.validate(), rgbl::ConfigError);
  rgbl::BruteForceMatchOptions b;
  CHECK_NOTHROW(b.validate());
  b.max_distance = 300;
  CHECK_THROWS_AS(b.validate(), rgbl::ConfigError);
  CHECK_THROWS_AS(rgbl::FeatureGrid({}, 0, 10), rgbl::ConfigError);
}
