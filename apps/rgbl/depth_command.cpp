// rgbl depth <dir> [input options] --out <dir>
// Completed depth maps as uint16 PNG (depth x 256) with colourised previews, and depth metrics against
// the dataset's own depth (synthetic, RGB-D) or, for LiDAR data with ground-truth poses, against the
// neighbouring scans accumulated into each frame (SPEC 3).
#include "command.hpp"
#include "input_options.hpp"

#include "rgbl/core/timer.hpp"
#include "rgbl/depth/completion.hpp"
#include "rgbl/depth/evaluation.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/io/read_ahead.hpp"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <map>
#include <memory>

namespace rgbl::cli {
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

Command add_depth_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "depth", "Write completed depth maps (uint16 PNG, depth x 256) and previews; report depth metrics");
  auto options = std::make_shared<PipelineOptions>();
  auto out_dir = std::make_shared<std::string>();
  auto half_window = std::make_shared<int>(5);
  add_input_options(*app, *options);
  app->add_option("--out", *out_dir, "Output folder (depth/ and preview/ are written inside)")->required();
  app->add_option("--gt-window", *half_window,
                  "LiDAR ground truth: accumulate the scans of +-N neighbouring frames (needs poses)")
      ->capture_default_str();
  return {app, [options, out_dir, half_window] {
            const Pipeline p(*options);
            for (const auto& note : p.notes()) fmt::print(stderr, "note: {}\n", note);
            const std::filesystem::path out(*out_dir);
            std::filesystem::create_directories(out / "depth");
            std::filesystem::create_directories(out / "preview");
            auto source = p.make_depth_source();
            const auto& gt = p.sequence().ground_truth();
            const bool lidar_gt = p.sequence().sensors().lidar && gt.has_value();
            ScanWindow window(p.sequence(), *half_window);
            AccumulationOptions accumulation;
            accumulation.half_window = *half_window;
            accumulation.projection = p.lidar_options().projection;
            DepthErrorAccumulator errors;
            double density_sum = 0.0, ms_sum = 0.0;
            std::size_t frames = 0, graded = 0;
            ReadAheadOptions read;
            read.first = p.first();
            read.count = p.frame_count();
            read.step = p.step();
            ReadAhead reader(p.sequence(), read);
            while (auto input = reader.next()) {
              Stopwatch watch;
              source->prepare(p.sensor_frame(*input));
              const cv::Mat_<float> dense = source->dense_depth();
              ms_sum += watch.elapsed_ms();
              density_sum += depth_density(dense);
              const std::string name = fmt::format("{:06d}.png", input->index);
              write_depth_png(out / "depth" / name, dense);
              cv::imwrite((out / "preview" / name).string(), colourise(dense, 80.0F));
              cv::Mat_<float> truth;
              if (!input->depth.empty() && p.depth_name() != "rgbd") {
                truth = input->depth;
              } else if (lidar_gt) {
                const auto scans = window.around(input->index);
                std::vector<Eigen::Isometry3d> poses(gt->poses.begin() + static_cast<std::ptrdiff_t>(window.first()),
                                                     gt->poses.begin() +
                                                         static_cast<std::ptrdiff_t>(window.first() + scans.size()));
                truth = accumulate_depth(p.calibration(), scans, poses, input->index - window.first(), accumulation);
              }
              if (!truth.empty()) {
                errors.add(dense, truth);
                ++graded;
              }
              ++frames;
            }
            fmt::print("{} frames, camera {}, depth {}: density {:.1f} %, {:.2f} ms per frame\n", frames, p.camera(),
                       options->depth, 100.0 * density_sum / std::max<std::size_t>(frames, 1),
                       ms_sum / std::max<std::size_t>(frames, 1));
            if (graded > 0) {
              const auto e = errors.result();
              fmt::print("against {} ({} frames, {} pixels, coverage {:.1f} %): MAE {:.3f} m, RMSE {:.3f} m, "
                         "iMAE {:.3f} 1/km, iRMSE {:.3f} 1/km\n",
                         lidar_gt ? fmt::format("LiDAR scans of +-{} frames", *half_window) : "the dataset's depth",
                         graded, e.count, 100.0 * e.coverage, e.mae, e.rmse, e.imae, e.irmse);
            } else {
              fmt::print("no ground-truth depth (needs poses and LiDAR scans, or depth images): no metrics\n");
            }
            fmt::print("depth maps in {}, previews in {}\n", (out / "depth").string(), (out / "preview").string());
            return 0;
          }};
}

}  // namespace rgbl::cli
