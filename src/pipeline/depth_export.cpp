#include "rgbl/pipeline/depth_export.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/depth/completion.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <map>

namespace rgbl {
namespace {

// Near = warm, far = cool, no depth = black; scaled on inverse depth so that near structure shows.
cv::Mat colourise(const cv::Mat_<float>& depth, float max_depth) {
  cv::Mat_<std::uint8_t> grey(depth.size(), std::uint8_t{0});
  const float inv_min = 1.0F / max_depth;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const float d = depth(v, u);
      if (d <= 0.0F) continue;
      const float t = std::clamp((1.0F / d - inv_min) / (1.0F / 5.0F - inv_min), 0.0F, 1.0F);
      grey(v, u) = static_cast<std::uint8_t>(1.0F + 254.0F * t);
    }
  }
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar::all(0), grey == 0);
  return colour;
}

// Neighbouring scans of one frame, loaded once while the window slides forward.
class ScanWindow {
 public:
  ScanWindow(const Sequence& sequence, int half_window) : sequence_(sequence), half_window_(half_window) {}

  std::vector<PointCloudView> around(std::size_t center) {
    const std::size_t lo = center >= static_cast<std::size_t>(half_window_) ? center - half_window_ : 0;
    const std::size_t hi = std::min(sequence_.size() - 1, center + static_cast<std::size_t>(half_window_));
    std::erase_if(scans_, [&](const auto& entry) { return entry.first < lo; });
    LoadOptions lidar_only;
    lidar_only.cameras = {false, false, false, false};
    lidar_only.depth = false;
    std::vector<PointCloudView> views;
    for (std::size_t j = lo; j <= hi; ++j) {
      auto it = scans_.find(j);
      if (it == scans_.end()) it = scans_.emplace(j, sequence_.load(j, lidar_only).scan).first;
      views.emplace_back(it->second);
    }
    first_ = lo;
    return views;
  }
  std::size_t first() const { return first_; }

 private:
  const Sequence& sequence_;
  int half_window_;
  std::map<std::size_t, std::vector<LidarPoint>> scans_;
  std::size_t first_ = 0;
};

}  // namespace

void DepthExportOptions::validate() const {
  require(ground_truth_half_window >= 0, "--gt-window", "a number of frames >= 0");
  require(preview_max_depth > 0.0F, "preview_max_depth", "a depth > 0 m");
}

DepthExportResult export_depth(const Pipeline& p, const std::filesystem::path& out,
                               const DepthExportOptions& options) {
  options.validate();
  const OutputFolder folder(out);  // checked and locked before the first frame, as a run's --out
  std::filesystem::create_directories(out / "depth");
  std::filesystem::create_directories(out / "preview");
  auto source = p.make_depth_source();
  const auto& gt = p.sequence().ground_truth();
  DepthExportResult result;
  result.lidar_ground_truth = p.sequence().sensors().lidar && gt.has_value();
  ScanWindow window(p.sequence(), options.ground_truth_half_window);
  AccumulationOptions accumulation;
  accumulation.half_window = options.ground_truth_half_window;
  accumulation.projection = p.lidar_options().projection;
  DepthErrorAccumulator errors;
  double density_sum = 0.0, ms_sum = 0.0;
  ReadAhead reader(p.sequence(), p.read_ahead_options());
  while (auto input = reader.next()) {
    Stopwatch watch;
    source->prepare(p.sensor_frame(*input));
    const cv::Mat_<float> dense = source->dense_depth();
    ms_sum += watch.elapsed_ms();
    density_sum += depth_density(dense);
    const std::string name = fmt::format("{:06d}.png", input->index);
    write_depth_png(out / "depth" / name, dense);
    const auto preview = out / "preview" / name;
    write_png_file(preview, colourise(dense, options.preview_max_depth));
    cv::Mat_<float> truth;
    if (!input->depth.empty() && p.depth_name() != "rgbd") {
      truth = input->depth;
    } else if (result.lidar_ground_truth) {
      const auto scans = window.around(input->index);
      std::vector<Eigen::Isometry3d> poses(gt->poses.begin() + static_cast<std::ptrdiff_t>(window.first()),
                                           gt->poses.begin() + static_cast<std::ptrdiff_t>(window.first() + scans.size()));
      truth = accumulate_depth(p.calibration(), scans, poses, input->index - window.first(), accumulation);
    }
    if (!truth.empty()) {
      errors.add(dense, truth);
      ++result.graded;
    }
    ++result.frames;
  }
  const double frames = static_cast<double>(std::max<std::size_t>(result.frames, 1));
  result.mean_density = density_sum / frames;
  result.mean_ms = ms_sum / frames;
  if (result.graded > 0) result.errors = errors.result();
  return result;
}

}  // namespace rgbl
