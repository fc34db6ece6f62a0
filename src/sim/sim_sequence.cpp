#include "rgbl/sim/sim_sequence.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>

namespace rgbl {
namespace {

class SimulatedSequence final : public Sequence {
 public:
  explicit SimulatedSequence(const SyntheticOptions& options) : generator_(options) {
    const SyntheticOptions& o = generator_.options();
    for (std::size_t c = 0; c < 4; ++c) sensors_.cameras[c] = o.cameras[c];
    sensors_.lidar = true;
    sensors_.depth = o.render_depth;
    Trajectory truth;
    for (int i = 0; i < o.frames; ++i) {
      truth.timestamps.push_back(generator_.timestamp(i));
      truth.poses.push_back(generator_.pose(i));
    }
    ground_truth_ = std::move(truth);
  }

  DatasetFormat format() const override { return DatasetFormat::kitti; }
  const std::string& name() const override { return name_; }
  const std::filesystem::path& path() const override { return path_; }
  std::size_t size() const override { return static_cast<std::size_t>(generator_.frame_count()); }
  const SensorSet& sensors() const override { return sensors_; }
  const KittiCalibration& calibration() const override { return generator_.calibration(); }
  double timestamp(std::size_t index) const override { return generator_.timestamp(checked(index)); }
  const std::optional<Trajectory>& ground_truth() const override { return ground_truth_; }
  const std::vector<std::string>& notes() const override { return notes_; }

  FrameInput load(std::size_t index) const override { return load(index, LoadOptions{}); }
  FrameInput load(std::size_t index, const LoadOptions& options) const override {
    const int i = checked(index);
    FrameInput f;
    f.index = index;
    f.timestamp = generator_.timestamp(i);
    for (std::size_t c = 0; c < 4; ++c) {
      if (options.cameras[c] && sensors_.cameras[c]) f.images[c] = generator_.render_image(i, static_cast<int>(c));
    }
    if (options.lidar) f.scan = generator_.render_scan(i);
    if (options.depth && sensors_.depth) f.depth = generator_.render_depth(i, generator_.options().depth_camera);
    f.T_world_cam0 = generator_.pose(i);
    return f;
  }

 private:
  int checked(std::size_t index) const {
    if (index >= size()) {
      throw ConfigError("frame", fmt::format("an index below {} (the synthetic drive's length), not {}", size(), index));
    }
    return static_cast<int>(index);
  }

  SyntheticGenerator generator_;
  SensorSet sensors_;
  std::optional<Trajectory> ground_truth_;
  std::string name_ = "synthetic";
  std::filesystem::path path_ = "<synthetic>";
  std::vector<std::string> notes_;
};

}  // namespace

std::unique_ptr<Sequence> make_synthetic_sequence(const SyntheticOptions& options) {
  return std::make_unique<SimulatedSequence>(options);
}

}  // namespace rgbl
