#include "file_sequence.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "text.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace rgbl::detail {
namespace {

class FileSequence final : public Sequence {
 public:
  FileSequence(SequenceTable table, const LoadOptions& options) : table_(std::move(table)), options_(options) {}

  DatasetFormat format() const override { return table_.format; }
  const std::string& name() const override { return table_.name; }
  const std::filesystem::path& path() const override { return table_.path; }
  std::size_t size() const override { return table_.frames.size(); }
  const SensorSet& sensors() const override { return table_.sensors; }
  const KittiCalibration& calibration() const override { return table_.calibration; }
  double timestamp(std::size_t index) const override { return table_.frames.at(index).timestamp; }
  const std::optional<Trajectory>& ground_truth() const override { return table_.ground_truth; }
  const std::vector<std::string>& notes() const override { return table_.notes; }

  FrameInput load(std::size_t index) const override { return load(index, options_); }

  FrameInput load(std::size_t index, const LoadOptions& options) const override {
    if (index >= size()) {
      throw Error(fmt::format("{}: frame {} requested, the sequence has {}", table_.path.string(), index, size()));
    }
    const FrameFiles& files = table_.frames[index];
    FrameInput frame;
    frame.index = index;
    frame.timestamp = files.timestamp;
    frame.T_world_cam0 = files.T_world_cam0;
    frame.scan_timestamp = files.scan_timestamp;
    for (std::size_t c = 0; c < 4; ++c) {
      if (!options.cameras[c] || files.images[c].empty()) continue;
      if (table_.grey_from_colour && c == 0) continue;  // converted below
      frame.images[c] = read_image(files.images[c], c < 2);
      check_size(frame.images[c], files.images[c], c);
    }
    if (table_.grey_from_colour && options.cameras[0] && !files.images[2].empty()) {
      cv::Mat colour = frame.images[2];
      if (colour.empty()) colour = read_image(files.images[2], false);
      check_size(colour, files.images[2], 2);
      cv::cvtColor(colour, frame.images[0], cv::COLOR_BGR2GRAY);
    }
    if (options.lidar && !files.scan.empty()) read_kitti_scan(files.scan, frame.scan);
    if (options.depth && !files.depth.empty()) frame.depth = read_depth(files.depth);
    return frame;
  }

 private:
  void check_size(const cv::Mat& image, const std::filesystem::path& file, std::size_t camera) const {
    const int w = table_.calibration.width[camera];
    const int h = table_.calibration.height[camera];
    if (image.cols != w || image.rows != h) {
      throw ParseError(file, 0,
                       fmt::format("image is {}x{}, expected {}x{} like the calibration and the first image of "
                                   "camera {}",
                                   image.cols, image.rows, w, h, camera));
    }
  }

  cv::Mat_<float> read_depth(const std::filesystem::path& file) const {
    const cv::Mat raw = read_image_file(file, ImageMode::grey_any_depth);
    if (raw.type() != CV_16UC1) throw ParseError(file, 0, "expected a 16-bit single-channel depth PNG");
    const int w = table_.calibration.width[2];
    const int h = table_.calibration.height[2];
    if (raw.cols != w || raw.rows != h) {
      throw ParseError(
          file, 0,
          fmt::format("depth image is {}x{}, expected {}x{} like the colour images", raw.cols, raw.rows, w, h));
    }
    cv::Mat_<float> depth;
    raw.convertTo(depth, CV_32F, 1.0 / table_.depth_factor);
    return depth;
  }

  SequenceTable table_;
  LoadOptions options_;
};

}  // namespace

std::unique_ptr<Sequence> make_file_sequence(SequenceTable table, const LoadOptions& options) {
  return std::make_unique<FileSequence>(std::move(table), options);
}

cv::Mat read_image(const std::filesystem::path& file, bool grey) {
  return read_image_file(file, grey ? ImageMode::grey : ImageMode::colour);
}

void set_image_sizes(SequenceTable& table) {
  if (table.frames.empty()) return;
  for (std::size_t c = 0; c < 4; ++c) {
    if (!table.sensors.cameras[c]) continue;
    if (table.grey_from_colour && c == 0) continue;
    const auto& file = table.frames.front().images[c];
    const cv::Mat first = read_image(file, c < 2);
    int& w = table.calibration.width[c];
    int& h = table.calibration.height[c];
    if (w > 0 && h > 0 && (first.cols != w || first.rows != h)) {
      throw ParseError(
          file, 0,
          fmt::format("image is {}x{}, but the calibration says {}x{} for camera {}", first.cols, first.rows, w, h, c));
    }
    w = first.cols;
    h = first.rows;
  }
  if (table.grey_from_colour) {
    table.calibration.width[0] = table.calibration.width[2];
    table.calibration.height[0] = table.calibration.height[2];
  }
  // now that the sizes are known: intrinsics that fit them (odometry calib.txt carries no size)
  for (std::size_t c = 0; c < 4; ++c) {
    if (!table.sensors.cameras[c] || table.calibration_file.empty()) continue;
    if (const auto why = table.calibration.camera(static_cast<int>(c)).camera.implausibility()) {
      throw ParseError(table.calibration_file, 0, fmt::format("camera {}: {}", c, *why));
    }
  }
}

void require_frames(const std::filesystem::path& dir, std::size_t count, int digits, std::string_view extension) {
  const auto present = numbered_files(dir, extension);
  std::size_t k = 0;
  for (std::size_t i = 0; i < count; ++i) {
    while (k < present.size() && present[k] < i) ++k;
    if (k == present.size() || present[k] != i) {
      throw ParseError(dir / fmt::format("{:0{}}{}", i, digits, extension), 0,
                       fmt::format("missing: frame {} of 0..{} (the sensor folders hold frames up to {}; "
                                   "incomplete download?)",
                                   i, count - 1, count - 1));
    }
  }
}

}  // namespace rgbl::detail

