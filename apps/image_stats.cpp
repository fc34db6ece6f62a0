// rgbl_image_stats [--every K] [--frames N] [--seed S] SOURCE...
// Simple statistics of camera 0's grey images and the LiDAR scans, to compare the synthetic scenarios
// with real KITTI frames (docs/synthetic.md, "Looks like KITTI"). SOURCE is a KITTI odometry sequence
// folder, a KITTI raw drive folder, or `scenario:NAME` (rendered in memory). Images larger than
// 700 px are halved first, so that real frames are compared at the synthetic street's 613x185.
// Prints one markdown table row per source: the mean over the frames of each statistic.
#include "rgbl/features/orb.hpp"
#include "rgbl/io/sequence.hpp"
#include "rgbl/sim/scenarios.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

namespace {

struct Frame {
  cv::Mat grey;                         // CV_8UC1
  std::vector<rgbl::LidarPoint> scan;   // LiDAR frame
};

struct Source {
  std::string label;
  rgbl::PinholeCamera camera;           // of the (possibly halved) image
  Eigen::Isometry3d T_cam0_lidar = Eigen::Isometry3d::Identity();
  std::vector<Frame> frames;
};

constexpr int kStats = 12;
constexpr std::array<const char*, kStats> kNames = {"mean", "std", "grad p50", "grad p90", "grad p99", "ORB",
                                                     "FAST20", "sky %", "road %", "LiDAR in image", "lap var",
                                                     "lap var (centre)"};

// Halves images wider than 700 px (INTER_AREA, as a camera of half the resolution would see them).
void halve_if_large(cv::Mat& grey, rgbl::PinholeCamera& cam) {
  if (grey.cols <= 700) return;
  const cv::Size size((grey.cols + 1) / 2, (grey.rows + 1) / 2);
  const double sx = static_cast<double>(size.width) / grey.cols, sy = static_cast<double>(size.height) / grey.rows;
  cv::resize(grey, grey, size, 0.0, 0.0, cv::INTER_AREA);
  cam.fx *= sx;
  cam.fy *= sy;
  cam.cx = (cam.cx + 0.5) * sx - 0.5;
  cam.cy = (cam.cy + 0.5) * sy - 0.5;
  cam.width = size.width;
  cam.height = size.height;
}

Source load_dataset(const std::string& dir, int every, int max_frames) {
  rgbl::LoadOptions load;
  load.cameras = {true, false, false, false};
  load.depth = false;
  const auto seq = rgbl::open_sequence(dir, rgbl::DatasetFormat::automatic, load);
  Source s;
  s.label = seq->path().filename().string();
  s.T_cam0_lidar = seq->calibration().T_cam0_lidar;
  for (std::size_t i = 0; i < seq->size() && static_cast<int>(s.frames.size()) < max_frames;
       i += static_cast<std::size_t>(every)) {
    rgbl::FrameInput in = seq->load(i);
    rgbl::PinholeCamera cam = seq->calibration().camera(0).camera;
    Frame f{in.images[0].clone(), std::move(in.scan)};
    halve_if_large(f.grey, cam);
    s.camera = cam;
    s.frames.push_back(std::move(f));
  }
  return s;
}

Source render_scenario(const std::string& name, std::uint64_t seed, int every, int max_frames) {
  rgbl::SyntheticOptions o = rgbl::scenario_options(name, seed);
  o.cameras = {true, false, false, false};
  o.render_depth = false;
  const rgbl::SyntheticGenerator g(o);
  Source s;
  s.label = "scenario " + name;
  s.camera = g.calibration().camera(0).camera;
  s.T_cam0_lidar = g.calibration().T_cam0_lidar;
  for (int i = 0; i < o.frames && static_cast<int>(s.frames.size()) < max_frames; i += every) {
    s.frames.push_back({g.render_image(i, 0), g.render_scan(i)});
  }
  return s;
}

double percentile(std::vector<float> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double laplacian_variance(const cv::Mat& grey) {
  cv::Mat lap;
  cv::Laplacian(grey, lap, CV_64F);
  cv::Scalar mean, sd;
  cv::meanStdDev(lap, mean, sd);
  return sd[0] * sd[0];
}

std::array<double, kStats> frame_stats(const Frame& f, const Source& src, rgbl::OrbExtractor& orb) {
  std::array<double, kStats> r{};
  const cv::Mat& g = f.grey;
  cv::Scalar mean, sd;
  cv::meanStdDev(g, mean, sd);
  r[0] = mean[0];
  r[1] = sd[0];
  cv::Mat gx, gy, mag;
  cv::Sobel(g, gx, CV_32F, 1, 0);
  cv::Sobel(g, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, mag);
  std::vector<float> m(mag.begin<float>(), mag.end<float>());
  r[2] = percentile(m, 0.5);
  r[3] = percentile(m, 0.9);
  r[4] = percentile(m, 0.99);
  std::vector<rgbl::Keypoint> kps;
  std::vector<rgbl::Descriptor> desc;
  orb.extract(g, kps, desc);
  r[5] = static_cast<double>(kps.size());
  std::vector<cv::KeyPoint> fast;
  cv::FAST(g, fast, 20, true);
  r[6] = static_cast<double>(fast.size());

  // sky: bright, smooth pixels connected to the top border (a heuristic, the same for every source)
  cv::Mat candidate = (g >= 140) & (mag < 40.0F);
  cv::Mat sky = cv::Mat::zeros(g.rows + 2, g.cols + 2, CV_8U);
  for (int u = 0; u < g.cols; ++u) {
    if (candidate.at<std::uint8_t>(0, u) != 0 && sky.at<std::uint8_t>(1, u + 1) == 0) {
      cv::floodFill(candidate, sky, cv::Point(u, 0), cv::Scalar(255), nullptr, cv::Scalar(0), cv::Scalar(0),
                    4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
    }
  }
  r[7] = 100.0 * cv::countNonZero(sky(cv::Rect(1, 1, g.cols, g.rows))) / static_cast<double>(g.total());

  // road: pixels nearest (z-buffered 7x7 splats) to LiDAR returns within 25 cm of the road plane,
  // 1.65 m below the camera (KITTI's camera height, the synthetic street's too)
  cv::Mat_<float> zbuf(g.rows, g.cols, 1e9F);
  cv::Mat_<std::uint8_t> label(g.rows, g.cols, std::uint8_t{0});
  int in_image = 0;
  const rgbl::PinholeCamera& cam = src.camera;
  for (const rgbl::LidarPoint& p : f.scan) {
    const Eigen::Vector3d c = src.T_cam0_lidar * Eigen::Vector3d(p.x, p.y, p.z);
    if (c.z() < 0.5) continue;
    const double u = cam.fx * c.x() / c.z() + cam.cx, v = cam.fy * c.y() / c.z() + cam.cy;
    const int iu = static_cast<int>(std::lround(u)), iv = static_cast<int>(std::lround(v));
    if (iu < 0 || iv < 0 || iu >= g.cols || iv >= g.rows) continue;
    ++in_image;
    const std::uint8_t kind = std::abs(c.y() - 1.65) < 0.25 ? 1 : 2;
    for (int dv = -3; dv <= 3; ++dv) {
      for (int du = -3; du <= 3; ++du) {
        const int x = iu + du, y = iv + dv;
        if (x < 0 || y < 0 || x >= g.cols || y >= g.rows || zbuf(y, x) <= c.z()) continue;
        zbuf(y, x) = static_cast<float>(c.z());
        label(y, x) = kind;
      }
    }
  }
  r[8] = 100.0 * cv::countNonZero(label == 1) / static_cast<double>(g.total());
  r[9] = in_image;
  r[10] = laplacian_variance(g);
  r[11] = laplacian_variance(g(cv::Rect(g.cols / 4, g.rows / 4, g.cols / 2, g.rows / 2)));
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Image and LiDAR statistics of KITTI folders and synthetic scenarios (markdown rows)"};
  std::vector<std::string> sources;
  int every = 5, max_frames = 12;
  std::uint64_t seed = 1;
  app.add_option("sources", sources, "KITTI odometry sequence or raw drive folders, or scenario:NAME")->required();
  app.add_option("--every", every, "use every K-th frame")->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("--frames", max_frames, "at most this many frames per source")->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the scenarios")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    std::string header = "| source | frames | size |";
    std::string rule = "|---|---|---|";
    for (const char* n : kNames) {
      header += fmt::format(" {} |", n);
      rule += "---|";
    }
    fmt::print("{}\n{}\n", header, rule);
    rgbl::OrbExtractor orb;
    for (const std::string& name : sources) {
      const Source src = name.rfind("scenario:", 0) == 0 ? render_scenario(name.substr(9), seed, every, max_frames)
                                                         : load_dataset(name, every, max_frames);
      std::array<double, kStats> sum{};
      for (const Frame& f : src.frames) {
        const auto r = frame_stats(f, src, orb);
        for (int k = 0; k < kStats; ++k) sum[static_cast<std::size_t>(k)] += r[static_cast<std::size_t>(k)];
      }
      const double n = static_cast<double>(std::max<std::size_t>(1, src.frames.size()));
      std::string row = fmt::format("| {} | {} | {}x{} |", src.label, src.frames.size(), src.camera.width,
                                    src.camera.height);
      for (int k = 0; k < kStats; ++k) {
        const double v = sum[static_cast<std::size_t>(k)] / n;
        row += v >= 100.0 ? fmt::format(" {:.0f} |", v) : fmt::format(" {:.1f} |", v);
      }
      fmt::print("{}\n", row);
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_image_stats: {}\n", e.what());
    return 1;
  }
  return 0;
}
