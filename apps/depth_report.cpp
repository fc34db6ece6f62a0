// rgbl_depth_report [--data <dir>] [--frames <n>] [--half-window <k>]
// Depth completion on real KITTI data (odometry sequence 04 under <dir>, default ../shared/data):
// projects each scan into camera 2, completes it with every dilation kernel and with IP-Basic, runs
// SGBM on the grey stereo pair (camera 0), and grades all of them against ground truth accumulated
// from the neighbouring scans (+-k frames, ground-truth poses, the frame's own scan left out).
// Prints a markdown table; everything runs on one thread.
#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/depth/completion.hpp"
#include "rgbl/depth/evaluation.hpp"
#include "rgbl/depth/ip_basic.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/projection.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace {

struct Row {
  std::string method;
  double density_sum = 0.0;
  rgbl::DepthErrorAccumulator errors;
  std::vector<double> ms;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void print_row(const Row& row, std::size_t frames) {
  const rgbl::DepthErrors e = row.errors.result();
  fmt::print("| {} | {:.1f} | {:.1f} | {:.3f} | {:.3f} | {:.2f} | {:.2f} | {} |\n", row.method,
             100.0 * row.density_sum / static_cast<double>(frames), 100.0 * e.coverage, e.mae, e.rmse, e.imae, e.irmse,
             row.ms.empty() ? std::string("-") : fmt::format("{:.3f}", median(row.ms)));
}

}  // namespace

int main(int argc, char** argv) try {
  std::filesystem::path data = "../shared/data";
  if (const char* env = std::getenv("RGBL_DATA_DIR"); env != nullptr && *env != '\0') data = env;
  int frame_limit = 51;
  int half_window = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 < argc && arg == "--data") data = argv[++i];
    else if (i + 1 < argc && arg == "--frames") frame_limit = std::stoi(argv[++i]);
    else if (i + 1 < argc && arg == "--half-window") half_window = std::stoi(argv[++i]);
    else {
      fmt::print(stderr, "usage: rgbl_depth_report [--data <dir>] [--frames <n>] [--half-window <k>]\n");
      return 2;
    }
  }
  cv::setNumThreads(1);
  const auto seq = data / "kitti/odometry/sequences/04";
  const auto kitti = rgbl::read_kitti_odometry_calibration(seq / "calib.txt", 1226, 370);  // 04-12: 1226x370
  const auto all_poses = rgbl::read_kitti_trajectory(data / "kitti/odometry/poses/04.txt");
  std::vector<std::vector<rgbl::LidarPoint>> scans;
  for (int i = 0; i < frame_limit; ++i) {
    const auto file = seq / "velodyne" / fmt::format("{:06d}.bin", i);
    if (!std::filesystem::exists(file)) break;
    scans.push_back(rgbl::read_kitti_scan(file));
  }
  const std::size_t frames = scans.size();
  if (frames == 0) throw rgbl::ParseError(seq / "velodyne", 0, "KITTI scans 000000.bin ...");
  std::vector<rgbl::PointCloudView> views(scans.begin(), scans.end());
  const std::vector<Eigen::Isometry3d> poses(all_poses.begin(), all_poses.begin() + static_cast<std::ptrdiff_t>(frames));

  const auto cam2 = kitti.camera(2);
  const auto cam0 = kitti.camera(0);
  rgbl::AccumulationOptions accumulation;
  accumulation.half_window = half_window;

  std::vector<rgbl::DilationOptions> kernels;
  for (int size : {3, 5, 7, 9}) kernels.push_back({rgbl::KernelShape::diamond, size, 200.0F});
  for (int size : {3, 5}) kernels.push_back({rgbl::KernelShape::rectangle, size, 200.0F});
  for (int size : {3, 5, 7}) kernels.push_back({rgbl::KernelShape::cross, size, 200.0F});

  Row sparse_row{"projection only (input)", 0.0, {}, {}};
  std::vector<Row> kernel_rows;
  for (const auto& k : kernels) kernel_rows.push_back({"inverse dilation, " + k.kernel().name(), 0.0, {}, {}});
  Row fast_row{"IP-Basic fast", 0.0, {}, {}}, multiscale_row{"IP-Basic multiscale", 0.0, {}, {}};
  Row stereo_row{"stereo SGBM (camera 0)", 0.0, {}, {}};
  double gt_density = 0.0, gt0_density = 0.0;

  rgbl::DepthSourceContext stereo_settings;
  stereo_settings.calibration = cam0;
  stereo_settings.stereo_baseline = kitti.baseline(0, 1);
  auto stereo = rgbl::make_stereo_source({}, stereo_settings);

  std::vector<cv::Mat_<float>> dense_buffers(kernels.size());
  for (auto& buffer : dense_buffers) buffer = cv::Mat_<float>(cam2.camera.height, cam2.camera.width, 0.0F);
  for (std::size_t i = 0; i < frames; ++i) {
    const cv::Mat_<float> gt = rgbl::accumulate_depth(cam2, views, poses, i, accumulation);
    gt_density += rgbl::depth_density(gt);
    rgbl::Stopwatch watch;
    const cv::Mat_<float> sparse =
        rgbl::project_to_depth(views[i], cam2.P_img_lidar(), cam2.camera.width, cam2.camera.height);
    sparse_row.ms.push_back(watch.elapsed_ms());
    sparse_row.density_sum += rgbl::depth_density(sparse);
    sparse_row.errors.add(sparse, gt);
    for (std::size_t k = 0; k < kernels.size(); ++k) {
      cv::Mat_<float>& dense = dense_buffers[k];  // reused across frames, as a depth source does
      watch.restart();
      rgbl::dilate_depth(sparse, kernels[k], dense);
      kernel_rows[k].ms.push_back(watch.elapsed_ms());
      kernel_rows[k].density_sum += rgbl::depth_density(dense);
      kernel_rows[k].errors.add(dense, gt);
    }
    watch.restart();
    const cv::Mat_<float> fast = rgbl::ip_basic_fast(sparse);
    fast_row.ms.push_back(watch.elapsed_ms());
    fast_row.density_sum += rgbl::depth_density(fast);
    fast_row.errors.add(fast, gt);
    watch.restart();
    const cv::Mat_<float> multiscale = rgbl::ip_basic_multiscale(sparse);
    multiscale_row.ms.push_back(watch.elapsed_ms());
    multiscale_row.density_sum += rgbl::depth_density(multiscale);
    multiscale_row.errors.add(multiscale, gt);

    // stereo depth lives in camera 0: graded against camera 0's accumulated ground truth
    const cv::Mat_<float> gt0 = rgbl::accumulate_depth(cam0, views, poses, i, accumulation);
    gt0_density += rgbl::depth_density(gt0);
    rgbl::SensorFrame frame;
    frame.index = i;
    frame.image = cv::imread((seq / "image_0" / fmt::format("{:06d}.png", i)).string(), cv::IMREAD_GRAYSCALE);
    frame.image_right = cv::imread((seq / "image_1" / fmt::format("{:06d}.png", i)).string(), cv::IMREAD_GRAYSCALE);
    watch.restart();
    stereo->prepare(frame);
    stereo_row.ms.push_back(watch.elapsed_ms());
    const cv::Mat_<float> stereo_depth = stereo->dense_depth();
    stereo_row.density_sum += rgbl::depth_density(stereo_depth);
    stereo_row.errors.add(stereo_depth, gt0);
  }

  fmt::print("KITTI odometry 04, frames 0-{} ({} frames), 1226x370; ground truth: scans of frames i-{}..i+{} "
             "without frame i, z-buffered (density {:.1f}% in camera 2, {:.1f}% in camera 0)\n\n",
             frames - 1, frames, half_window, half_window, 100.0 * gt_density / static_cast<double>(frames),
             100.0 * gt0_density / static_cast<double>(frames));
  fmt::print("| method | density % | GT covered % | MAE m | RMSE m | iMAE 1/km | iRMSE 1/km | ms/frame (median) |\n");
  fmt::print("|---|---|---|---|---|---|---|---|\n");
  print_row(sparse_row, frames);
  for (const auto& row : kernel_rows) print_row(row, frames);
  print_row(fast_row, frames);
  print_row(multiscale_row, frames);
  print_row(stereo_row, frames);
  return 0;
} catch (const std::exception& e) {
  fmt::print(stderr, "rgbl_depth_report: {}\n", e.what());
  return 1;
}
