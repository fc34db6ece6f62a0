#include "rgbl/core/error.hpp"
#include "rgbl/io/read_ahead.hpp"

#include <catch2/catch.hpp>

#include <atomic>
#include <stdexcept>

using Catch::Matchers::Contains;

namespace {

// Frames 0..n-1 whose timestamp is the index; load(fail_at) throws. Counts the loads.
class CountingSequence final : public rgbl::Sequence {
 public:
  CountingSequence(std::size_t n, std::size_t fail_at) : n_(n), fail_at_(fail_at) {}
  rgbl::DatasetFormat format() const override { return rgbl::DatasetFormat::kitti; }
  const std::string& name() const override { return name_; }
  const std::filesystem::path& path() const override { return path_; }
  std::size_t size() const override { return n_; }
  const rgbl::SensorSet& sensors() const override { return sensors_; }
  const rgbl::KittiCalibration& calibration() const override { return calibration_; }
  double timestamp(std::size_t i) const override { return static_cast<double>(i); }
  const std::optional<rgbl::Trajectory>& ground_truth() const override { return gt_; }
  const std::vector<std::string>& notes() const override { return notes_; }
  rgbl::FrameInput load(std::size_t i, const rgbl::LoadOptions&) const override { return load(i); }
  rgbl::FrameInput load(std::size_t i) const override {
    ++loads;
    if (i == fail_at_) throw rgbl::ParseError(fmt_path(i), 0, "broken on purpose");
    rgbl::FrameInput f;
    f.index = i;
    f.timestamp = static_cast<double>(i);
    f.scan.resize(i + 1);
    return f;
  }
  mutable std::atomic<std::size_t> loads{0};

 private:
  static std::filesystem::path fmt_path(std::size_t i) { return "frame" + std::to_string(i) + ".bin"; }
  std::size_t n_, fail_at_;
  std::string name_ = "counting";
  std::filesystem::path path_;
  rgbl::SensorSet sensors_;
  rgbl::KittiCalibration calibration_;
  std::optional<rgbl::Trajectory> gt_;
  std::vector<std::string> notes_;
};

}  // namespace

TEST_CASE("read-ahead delivers every frame in order, then nothing", "[io][read-ahead]") {
  CountingSequence seq(20, 1000);
  rgbl::ReadAhead reader(seq, {2, 0, 0});
  for (std::size_t i = 0; i < 20; ++i) {
    auto f = reader.next();
    REQUIRE(f);
    CHECK(f->index == i);
    CHECK(f->scan.size() == i + 1);
  }
  CHECK_FALSE(reader.next());
  CHECK_FALSE(reader.next());
  CHECK(seq.loads == 20);
}

TEST_CASE("read-ahead honours first and count", "[io][read-ahead]") {
  CountingSequence seq(10, 1000);
  rgbl::ReadAhead reader(seq, {3, 4, 3});
  CHECK(reader.next()->index == 4);
  CHECK(reader.next()->index == 5);
  CHECK(reader.next()->index == 6);
  CHECK_FALSE(reader.next());
  rgbl::ReadAhead past_end(seq, {3, 8, 5});
  CHECK(past_end.next()->index == 8);
  CHECK(past_end.next()->index == 9);
  CHECK_FALSE(past_end.next());
}

TEST_CASE("read-ahead honours a step, with first and count, and skips the frames between", "[io][read-ahead]") {
  CountingSequence seq(10, 1000);
  rgbl::ReadAhead every_third(seq, {2, 1, 0, 3});
  CHECK(every_third.next()->index == 1);
  CHECK(every_third.next()->index == 4);
  CHECK(every_third.next()->index == 7);
  CHECK_FALSE(every_third.next());  // 10 is past the end
  CHECK(seq.loads == 3);            // frames between are never loaded
  rgbl::ReadAhead counted(seq, {2, 0, 2, 4});
  CHECK(counted.next()->index == 0);
  CHECK(counted.next()->index == 4);
  CHECK_FALSE(counted.next());
  rgbl::ReadAhead last_only(seq, {2, 9, 0, 5});
  CHECK(last_only.next()->index == 9);
  CHECK_FALSE(last_only.next());
  CHECK_THROWS_WITH(rgbl::ReadAhead(seq, {2, 0, 0, 0}), Contains("read_ahead.step"));
}

TEST_CASE("read-ahead forwards a load error on the frame that failed", "[io][read-ahead]") {
  CountingSequence seq(10, 3);
  rgbl::ReadAhead reader(seq, {4, 0, 0});
  for (std::size_t i = 0; i < 3; ++i) CHECK(reader.next()->index == i);
  CHECK_THROWS_WITH(reader.next(), Contains("frame3.bin") && Contains("broken on purpose"));
  CHECK_FALSE(reader.next());  // nothing after the failure
  CHECK(seq.loads == 4);
}

TEST_CASE("read-ahead stays within its bound and stops cleanly when abandoned", "[io][read-ahead]") {
  CountingSequence seq(1000, 100000);
  {
    rgbl::ReadAhead reader(seq, {2, 0, 0});
    CHECK(reader.next()->index == 0);
    // at most the one delivered and 2 queued are ever loaded
    for (int spin = 0; spin < 1000 && seq.loads < 3; ++spin) std::this_thread::yield();
  }  // destructor joins while the loader waits on a full queue
  CHECK(seq.loads <= 3);
  CHECK_THROWS_AS(rgbl::ReadAhead(seq, {0, 0, 0}), rgbl::ConfigError);
}
