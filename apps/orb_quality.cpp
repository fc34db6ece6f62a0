// rgbl_orb_quality [<kitti-sequence-dir> [<pairs> [<features_per_node> [<spread_fraction> [<fast_threshold> <fast_min_threshold>]]]]]
// Feature quality on consecutive frame pairs of a KITTI odometry sequence (default: seq 04 under
// ../shared/data, 50 pairs of image_0): rgbl's ORB extractor against cv::ORB with the same feature
// count, both matched by the same matchers:
//  - global: brute force over the whole frame (ratio 0.8, cross check), as for initialisation;
//  - guided: as in tracking, every keypoint of frame a with LiDAR depth (nearest sample within 2 px
//    of the sparse depth of the velodyne scan) is predicted into frame b with the ground-truth motion
//    and matched by match_guided (radius 15 px x scale^level, ratio 0.8, rotation histogram).
// A match "agrees with the true motion" when its Sampson distance to the epipolar geometry of the
// ground-truth relative pose is below 1 px; a fundamental-matrix RANSAC (1 px, 0.999) is reported
// for the global matches as well. "guided Sampson" is the median Sampson distance of the guided matches
// that agree: how precisely a keypoint lands on the same structure in both frames.
#include "rgbl/core/timer.hpp"
#include "rgbl/features/matcher.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/projection.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Features {
  std::vector<cv::Point2f> points;
  std::vector<rgbl::Keypoint> keypoints;
  std::vector<rgbl::Descriptor> descriptors;
  cv::Mat_<float> depth;  // sparse LiDAR depth of the frame
};

struct Totals {
  double features = 0, matches = 0, gt_inliers = 0, ransac_inliers = 0, extract_ms = 0;
  double occupied = 0;  // share of a 32 x 10 grid's cells (~38 px) holding a keypoint, summed over frames
  double guided_queries = 0, guided_matches = 0, guided_gt_inliers = 0;
  std::vector<double> guided_sampson;  // of the agreeing guided matches, px
  int pairs = 0;
};

// Depth of the LiDAR sample nearest to (x, y) within 2 px, or 0.
float depth_near(const cv::Mat_<float>& depth, float x, float y) {
  const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
  float best = 0.0F;
  int best_d2 = 1 << 30;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      const int u = cx + dx, v = cy + dy;
      if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
      const float z = depth(v, u);
      if (z > 0.0F && dx * dx + dy * dy < best_d2) {
        best = z;
        best_d2 = dx * dx + dy * dy;
      }
    }
  }
  return best;
}

std::vector<Eigen::Isometry3d> read_poses(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<Eigen::Isometry3d> poses;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    rgbl::Matrix34d m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) ss >> m(r, c);
    }
    if (ss) poses.push_back(rgbl::isometry_from_3x4(m));
  }
  return poses;
}

// F with p_a^T F p_b = 0 for pixels of frame a and b, from camera-to-world poses of both.
Eigen::Matrix3d fundamental(const Eigen::Matrix3d& K, const Eigen::Isometry3d& T_w_a, const Eigen::Isometry3d& T_w_b) {
  const Eigen::Isometry3d T_a_b = T_w_a.inverse() * T_w_b;
  const Eigen::Matrix3d E = rgbl::hat(T_a_b.translation()) * T_a_b.rotation();
  const Eigen::Matrix3d K_inv = K.inverse();
  return K_inv.transpose() * E * K_inv;
}

double sampson_px(const Eigen::Matrix3d& F, const cv::Point2f& a, const cv::Point2f& b) {
  const Eigen::Vector3d pa(a.x, a.y, 1.0), pb(b.x, b.y, 1.0);
  const Eigen::Vector3d Fb = F * pb, Fta = F.transpose() * pa;
  const double e = pa.dot(Fb);
  return std::abs(e) / std::sqrt(Fb.x() * Fb.x() + Fb.y() * Fb.y() + Fta.x() * Fta.x() + Fta.y() * Fta.y());
}

void accumulate_guided(Totals& t, const Features& a, const Features& b, const rgbl::PinholeCamera& camera,
                       const Eigen::Isometry3d& T_b_a, const Eigen::Matrix3d& F, int width, int height) {
  std::vector<rgbl::GuidedQuery> queries;
  std::vector<int> source;
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    const auto& k = a.keypoints[i];
    const float z = depth_near(a.depth, k.x, k.y);
    if (z <= 0.0F) continue;
    const Eigen::Vector3d p_b = T_b_a * camera.unproject(Eigen::Vector2d(k.x, k.y), z);
    if (p_b.z() < 0.5) continue;
    const Eigen::Vector2d px = camera.project_unchecked(p_b);
    rgbl::GuidedQuery q;
    q.x = static_cast<float>(px.x());
    q.y = static_cast<float>(px.y());
    q.level = k.level;
    q.angle = k.angle;
    q.descriptor = &a.descriptors[i];
    queries.push_back(q);
    source.push_back(static_cast<int>(i));
  }
  const rgbl::FeatureGrid grid(b.keypoints, width, height);
  const auto result = rgbl::match_guided(queries, grid, b.keypoints, b.descriptors, rgbl::GuidedMatchOptions{});
  t.guided_queries += static_cast<double>(queries.size());
  for (std::size_t q = 0; q < result.size(); ++q) {
    if (result[q] < 0) continue;
    t.guided_matches += 1.0;
    const auto& pa = a.points[static_cast<std::size_t>(source[q])];
    const auto& pb = b.points[static_cast<std::size_t>(result[q])];
    const double sampson = sampson_px(F, pa, pb);
    if (sampson < 1.0) {
      t.guided_gt_inliers += 1.0;
      t.guided_sampson.push_back(sampson);
    }
  }
}

void accumulate(Totals& t, const Features& a, const Features& b, const Eigen::Matrix3d* F) {
  rgbl::BruteForceMatchOptions options;
  options.ratio = 0.8F;
  options.cross_check = true;
  const auto matches = rgbl::match_brute_force(a.descriptors, b.descriptors, options);
  t.features += 0.5 * static_cast<double>(a.points.size() + b.points.size());
  {
    constexpr int kCols = 32, kRows = 10;
    std::vector<char> cells(kCols * kRows, 0);
    for (const auto& p : a.points) {
      const int cx = std::clamp(static_cast<int>(p.x * kCols / static_cast<float>(a.depth.cols)), 0, kCols - 1);
      const int cy = std::clamp(static_cast<int>(p.y * kRows / static_cast<float>(a.depth.rows)), 0, kRows - 1);
      cells[static_cast<std::size_t>(cy * kCols + cx)] = 1;
    }
    t.occupied += static_cast<double>(std::count(cells.begin(), cells.end(), 1)) / (kCols * kRows);
  }
  t.matches += static_cast<double>(matches.size());
  std::vector<cv::Point2f> pa, pb;
  for (const auto& m : matches) {
    pa.push_back(a.points[static_cast<std::size_t>(m.query)]);
    pb.push_back(b.points[static_cast<std::size_t>(m.train)]);
    if (F != nullptr && sampson_px(*F, pa.back(), pb.back()) < 1.0) t.gt_inliers += 1.0;
  }
  if (pa.size() >= 8) {
    std::vector<unsigned char> mask;
    cv::findFundamentalMat(pa, pb, cv::FM_RANSAC, 1.0, 0.999, mask);
    for (const auto v : mask) t.ransac_inliers += v != 0 ? 1.0 : 0.0;
  }
  ++t.pairs;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

void print_row(const char* name, const Totals& t) {
  const double n = t.pairs;
  fmt::print("| {:<8} | {:8.0f} | {:7.1f}% | {:9.2f} | {:8.1f} | {:>16} | {:>16} | {:8.1f} | {:8.1f} | {:>16} | {:.3f} |\n", name,
             t.features / n, 100.0 * t.occupied / n, t.extract_ms / n, t.matches / n,
             fmt::format("{:.1f} ({:.1f}%)", t.gt_inliers / n, 100.0 * t.gt_inliers / t.matches),
             fmt::format("{:.1f} ({:.1f}%)", t.ransac_inliers / n, 100.0 * t.ransac_inliers / t.matches),
             t.guided_queries / n, t.guided_matches / n,
             fmt::format("{:.1f} ({:.1f}%)", t.guided_gt_inliers / n, 100.0 * t.guided_gt_inliers / t.guided_matches),
             median(t.guided_sampson));
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::filesystem::path seq = argc > 1 ? argv[1] : "../shared/data/kitti/odometry/sequences/04";
    const int pairs = argc > 2 ? std::stoi(argv[2]) : 50;
    rgbl::OrbOptions orb_options;
    if (argc > 3) orb_options.features_per_node = std::stoi(argv[3]);
    if (argc > 4) orb_options.spread_fraction = std::stod(argv[4]);
    if (argc > 5) orb_options.fast_threshold = std::stoi(argv[5]);
    if (argc > 6) orb_options.fast_min_threshold = std::stoi(argv[6]);
    // Ground truth beside the sequences folder, as in the KITTI odometry layout.
    const std::filesystem::path poses_file =
        seq.parent_path().parent_path() / "poses" / (seq.filename().string() + ".txt");
    const auto calib = rgbl::read_kitti_odometry_calibration(seq / "calib.txt");
    const Eigen::Matrix3d K = calib.P[0].leftCols<3>();
    const auto poses = read_poses(poses_file);
    if (static_cast<int>(poses.size()) <= pairs) throw std::runtime_error("too few poses in " + poses_file.string());
    const rgbl::CameraCalibration cam0 = calib.camera(0);
    rgbl::ProjectionOptions projection;
    projection.min_depth = 1.0F;
    std::vector<rgbl::LidarPoint> scan;

    cv::setNumThreads(1);
    rgbl::OrbExtractor extractor(orb_options);
    auto cv_orb = cv::ORB::create(2000, 1.2F, 8);
    Totals ours, theirs;
    Features prev_ours, prev_theirs;
    std::vector<cv::KeyPoint> cv_keypoints;
    cv::Mat cv_descriptors;
    for (int frame = 0; frame <= pairs; ++frame) {
      const std::string name = fmt::format("{:06d}.png", frame);
      const cv::Mat img = cv::imread((seq / "image_0" / name).string(), cv::IMREAD_GRAYSCALE);
      if (img.empty()) throw std::runtime_error("cannot read " + (seq / "image_0" / name).string());
      rgbl::read_kitti_scan(seq / "velodyne" / fmt::format("{:06d}.bin", frame), scan);
      const cv::Mat_<float> depth =
          rgbl::project_to_depth(scan, cam0.P_img_lidar(), img.cols, img.rows, projection);
      Features cur_ours, cur_theirs;
      cur_ours.depth = depth;
      cur_theirs.depth = depth;
      rgbl::Stopwatch watch;
      extractor.extract(img, cur_ours.keypoints, cur_ours.descriptors);
      if (frame > 0) ours.extract_ms += watch.lap_ms();
      for (const auto& k : cur_ours.keypoints) cur_ours.points.emplace_back(k.x, k.y);
      watch.restart();
      cv_orb->detectAndCompute(img, cv::noArray(), cv_keypoints, cv_descriptors);
      if (frame > 0) theirs.extract_ms += watch.lap_ms();
      for (int i = 0; i < cv_descriptors.rows; ++i) {
        const cv::KeyPoint& ck = cv_keypoints[static_cast<std::size_t>(i)];
        rgbl::Descriptor d{};
        std::memcpy(d.data(), cv_descriptors.ptr<std::uint8_t>(i), d.size());
        cur_theirs.descriptors.push_back(d);
        cur_theirs.points.push_back(ck.pt);
        rgbl::Keypoint k;
        k.x = ck.pt.x;
        k.y = ck.pt.y;
        k.angle = ck.angle;
        k.response = ck.response;
        k.size = ck.size;
        k.level = ck.octave;
        cur_theirs.keypoints.push_back(k);
      }
      if (frame > 0) {
        const auto& T_w_a = poses[static_cast<std::size_t>(frame) - 1];
        const auto& T_w_b = poses[static_cast<std::size_t>(frame)];
        const Eigen::Matrix3d F = fundamental(K, T_w_a, T_w_b);
        const Eigen::Isometry3d T_b_a = T_w_b.inverse() * T_w_a;
        accumulate(ours, prev_ours, cur_ours, &F);
        accumulate(theirs, prev_theirs, cur_theirs, &F);
        accumulate_guided(ours, prev_ours, cur_ours, cam0.camera, T_b_a, F, img.cols, img.rows);
        accumulate_guided(theirs, prev_theirs, cur_theirs, cam0.camera, T_b_a, F, img.cols, img.rows);
      }
      prev_ours = std::move(cur_ours);
      prev_theirs = std::move(cur_theirs);
    }
    fmt::print("{} consecutive pairs of {} (image_0), 2000 features, 8 levels, scale 1.2, rgbl features_per_node {}, spread_fraction {}; "
               "mean per pair.\n"
               "global: brute force, ratio 0.8, cross check. guided: keypoints with LiDAR depth predicted with the "
               "ground-truth motion, match_guided defaults. agree = Sampson distance to the ground-truth epipolar "
               "geometry < 1 px. occupied cells: share of a 32 x 10 grid holding a keypoint.\n\n",
               pairs, seq.string(), orb_options.features_per_node, orb_options.spread_fraction);
    fmt::print("| extractor | features | occupied cells | ms/frame | global matches | global agree | F-RANSAC inliers | guided queries "
               "| guided matches | guided agree | guided Sampson px |\n");
    fmt::print("|---|---|---|---|---|---|---|---|---|---|---|\n");
    print_row("rgbl", ours);
    print_row("cv::ORB", theirs);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_orb_quality: {}\n", e.what());
    return 1;
  }
}
