// rgbl_orb_quality [<kitti-sequence-dir> [<pairs>] [<poses.txt>]]
// Feature quality on consecutive frame pairs of a KITTI odometry sequence (default: seq 04 under
// ../shared/data, 50 pairs of image_0): rgbl's ORB extractor against cv::ORB with the same feature
// count, both matched by the same brute-force matcher (ratio 0.8, cross check). A match "agrees with
// the true motion" when its Sampson distance to the epipolar geometry of the ground-truth relative
// pose is below 1 px; a fundamental-matrix RANSAC (1 px, 0.999) is reported as well.
#include "rgbl/core/timer.hpp"
#include "rgbl/features/matcher.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/geometry/calibration.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Features {
  std::vector<cv::Point2f> points;
  std::vector<rgbl::Descriptor> descriptors;
};

struct Totals {
  double features = 0, matches = 0, gt_inliers = 0, ransac_inliers = 0, extract_ms = 0;
  int pairs = 0;
};

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

void accumulate(Totals& t, const Features& a, const Features& b, const Eigen::Matrix3d* F) {
  rgbl::BruteForceMatchOptions options;
  options.ratio = 0.8F;
  options.cross_check = true;
  const auto matches = rgbl::match_brute_force(a.descriptors, b.descriptors, options);
  t.features += 0.5 * static_cast<double>(a.points.size() + b.points.size());
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

void print_row(const char* name, const Totals& t, bool have_gt) {
  const double n = t.pairs;
  fmt::print("| {:<10} | {:8.0f} | {:8.1f} | {:>22} | {:>22} | {:9.2f} |\n", name, t.features / n, t.matches / n,
             have_gt ? fmt::format("{:.1f} ({:.1f}%)", t.gt_inliers / n, 100.0 * t.gt_inliers / t.matches) : "n/a",
             fmt::format("{:.1f} ({:.1f}%)", t.ransac_inliers / n, 100.0 * t.ransac_inliers / t.matches),
             t.extract_ms / (2.0 * n));
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::filesystem::path seq = argc > 1 ? argv[1] : "../shared/data/kitti/odometry/sequences/04";
    const int pairs = argc > 2 ? std::stoi(argv[2]) : 50;
    const std::filesystem::path poses_file =
        argc > 3 ? std::filesystem::path(argv[3]) : seq.parent_path().parent_path() / "poses" / (seq.filename().string() + ".txt");
    const auto calib = rgbl::read_kitti_odometry_calibration(seq / "calib.txt");
    const Eigen::Matrix3d K = calib.P[0].leftCols<3>();
    const auto poses = read_poses(poses_file);
    const bool have_gt = static_cast<int>(poses.size()) > pairs;

    cv::setNumThreads(1);
    rgbl::OrbExtractor extractor;
    auto cv_orb = cv::ORB::create(2000, 1.2F, 8);
    Totals ours, theirs;
    Features prev_ours, prev_theirs;
    std::vector<rgbl::Keypoint> keypoints;
    std::vector<cv::KeyPoint> cv_keypoints;
    cv::Mat cv_descriptors;
    for (int frame = 0; frame <= pairs; ++frame) {
      const std::string name = fmt::format("{:06d}.png", frame);
      const cv::Mat img = cv::imread((seq / "image_0" / name).string(), cv::IMREAD_GRAYSCALE);
      if (img.empty()) throw std::runtime_error("cannot read " + (seq / "image_0" / name).string());
      Features cur_ours, cur_theirs;
      rgbl::Stopwatch watch;
      extractor.extract(img, keypoints, cur_ours.descriptors);
      ours.extract_ms += frame > 0 ? 2.0 * watch.lap_ms() : 0.0;
      for (const auto& k : keypoints) cur_ours.points.emplace_back(k.x, k.y);
      watch.restart();
      cv_orb->detectAndCompute(img, cv::noArray(), cv_keypoints, cv_descriptors);
      theirs.extract_ms += frame > 0 ? 2.0 * watch.lap_ms() : 0.0;
      for (int i = 0; i < cv_descriptors.rows; ++i) {
        rgbl::Descriptor d{};
        std::memcpy(d.data(), cv_descriptors.ptr<std::uint8_t>(i), d.size());
        cur_theirs.descriptors.push_back(d);
        cur_theirs.points.push_back(cv_keypoints[static_cast<std::size_t>(i)].pt);
      }
      if (frame > 0) {
        const Eigen::Matrix3d F = have_gt ? fundamental(K, poses[static_cast<std::size_t>(frame) - 1],
                                                        poses[static_cast<std::size_t>(frame)])
                                          : Eigen::Matrix3d::Zero();
        accumulate(ours, prev_ours, cur_ours, have_gt ? &F : nullptr);
        accumulate(theirs, prev_theirs, cur_theirs, have_gt ? &F : nullptr);
      }
      prev_ours = std::move(cur_ours);
      prev_theirs = std::move(cur_theirs);
    }
    fmt::print("{} consecutive pairs of {} (image_0), 2000 features, 8 levels, scale 1.2; brute force, ratio 0.8, "
               "cross check; mean per pair\n\n",
               pairs, seq.string());
    fmt::print("| extractor  | features |  matches | agree with GT motion   | F-RANSAC inliers       | ms/frame  |\n");
    fmt::print("|------------|----------|----------|------------------------|------------------------|-----------|\n");
    print_row("rgbl", ours, have_gt);
    print_row("cv::ORB", theirs, have_gt);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "rgbl_orb_quality: {}\n", e.what());
    return 1;
  }
}
