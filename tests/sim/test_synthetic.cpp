#include "rgbl/core/error.hpp"
#include "rgbl/geometry/projection.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

// Small frames keep the module's tests fast.
rgbl::SyntheticOptions small_options() {
  rgbl::SyntheticOptions o;
  o.frames = 3;
  o.width = 240;
  o.height = 72;
  return o;
}

bool same_bytes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

bool same_scan(const std::vector<rgbl::LidarPoint>& a, const std::vector<rgbl::LidarPoint>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(rgbl::LidarPoint)) == 0);
}

Eigen::Vector3d world_point(const rgbl::SyntheticGenerator& g, int frame, const rgbl::LidarPoint& p) {
  return g.pose(frame) * g.calibration().T_cam0_lidar * Eigen::Vector3d(p.x, p.y, p.z);
}

}  // namespace

TEST_CASE("same seed, same bytes, another seed, another street") {
  rgbl::SyntheticOptions o = small_options();
  o.frames = 2;
  const rgbl::SyntheticSequence a = rgbl::generate_sequence(o);
  o.threads = 1;  // the thread count must not matter
  const rgbl::SyntheticSequence b = rgbl::generate_sequence(o);
  REQUIRE(a.frames.size() == 2);
  for (std::size_t f = 0; f < 2; ++f) {
    for (std::size_t c = 0; c < 4; ++c) CHECK(same_bytes(a.frames[f].images[c], b.frames[f].images[c]));
    CHECK(same_bytes(a.frames[f].depth, b.frames[f].depth));
    CHECK(same_scan(a.frames[f].scan, b.frames[f].scan));
  }
  o.seed = 2;
  const rgbl::SyntheticSequence c = rgbl::generate_sequence(o);
  CHECK_FALSE(same_bytes(a.frames[1].images[0], c.frames[1].images[0]));
  CHECK_FALSE(same_bytes(a.frames[1].images[2], c.frames[1].images[2]));
  CHECK_FALSE(same_scan(a.frames[1].scan, c.frames[1].scan));
  // the road stays where it is: the seed changes the street, not the rig or the path
  CHECK(a.frames[1].T_world_cam0.isApprox(c.frames[1].T_world_cam0));
}

TEST_CASE("frames carry KITTI-like images, calibration and timestamps") {
  const rgbl::SyntheticGenerator g(small_options());
  const rgbl::SyntheticFrame f = g.render(2);
  CHECK(f.index == 2);
  CHECK_THAT(f.timestamp, WithinAbs(0.2, 1e-12));
  CHECK(f.images[0].type() == CV_8UC1);
  CHECK(f.images[1].type() == CV_8UC1);
  CHECK(f.images[2].type() == CV_8UC3);
  CHECK(f.images[3].type() == CV_8UC3);
  CHECK(f.images[0].cols == 240);
  CHECK(f.images[0].rows == 72);
  CHECK(f.depth.size() == f.images[2].size());
  const rgbl::KittiCalibration& cal = g.calibration();
  // KITTI 04's rig: 0.537 m grey baseline, camera 2 ~6 cm from cam0, intrinsics scaled by width/1226
  CHECK_THAT(cal.baseline(0, 1), WithinAbs(379.8145 / 707.0912, 1e-9));
  CHECK_THAT(cal.baseline(0, 2), WithinAbs(0.0614, 5e-4));
  CHECK_THAT(cal.camera(2).camera.fx, WithinAbs(707.0912 * 240.0 / 1226.0, 1e-9));
  CHECK(cal.P[2](0, 3) != 0.0);
  CHECK(cal.width[2] == 240);
  CHECK(cal.height[3] == 72);
  // the LiDAR sits above and behind the camera, as on KITTI: Tr's translation is the LiDAR in cam0
  const Eigen::Vector3d lidar_in_cam0 = cal.T_cam0_lidar.translation();
  CHECK(lidar_in_cam0.y() < -0.05);  // y down: above
  CHECK(lidar_in_cam0.z() < -0.3);   // behind
  // half of KITTI's size by default
  const rgbl::SyntheticOptions defaults;
  CHECK(defaults.width * 2 == 1226);
  CHECK(defaults.height * 2 == 370);
}

TEST_CASE("exact depth equals the analytic distance to the road plane") {
  rgbl::SyntheticOptions o = small_options();
  o.path.kind = rgbl::PathKind::curve;
  const rgbl::SyntheticGenerator g(o);
  for (const int camera : {2, 0}) {
    const rgbl::CameraCalibration cal = g.calibration().camera(camera);
    const rgbl::PinholeCamera& cam = cal.camera;
    // camera centre's height above the road: the road is y = 1.65 in cam0's frame (first pose)
    const double height = o.scene.camera_height - cal.T_cam_cam0.inverse().translation().y();
    const cv::Mat_<float> depth = g.render_depth(0, camera);
    int checked = 0;
    // the bottom rows, within 1.2 m of the track: the own lane ahead, where nothing stands
    for (int v = cam.height - 6; v < cam.height; ++v) {
      const double z = height / ((v - cam.cy) / cam.fy);
      const int half = static_cast<int>(1.2 * cam.fx / z);
      for (int u = static_cast<int>(cam.cx) - half; u <= static_cast<int>(cam.cx) + half; ++u) {
        const double expected = height / ((v - cam.cy) / cam.fy);
        REQUIRE_THAT(depth(v, u), WithinAbs(expected, 1e-5 * expected));
        ++checked;
      }
    }
    CHECK(checked > 150);
    // the sky has no depth
    int sky = 0;
    for (int u = 0; u < cam.width; ++u) sky += depth(0, u) == 0.0F ? 1 : 0;
    CHECK(sky > 0);
  }
}

TEST_CASE("noiseless LiDAR points lie on the surfaces they hit") {
  rgbl::SyntheticOptions o = small_options();
  o.lidar.range_noise_sigma = 0.0;
  const rgbl::SyntheticGenerator g(o);
  const std::vector<rgbl::LidarPoint> scan = g.render_scan(1);
  REQUIRE(scan.size() > 80000);  // 64 x 2000 rays, most hit the road or a building
  int on_road = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < scan.size(); i += 3) {
    const Eigen::Vector3d p = world_point(g, 1, scan[i]);
    worst = std::max(worst, std::abs(g.scene().signed_distance(p)));
    on_road += std::abs(p.y() - o.scene.camera_height) < 1e-4 ? 1 : 0;
    REQUIRE(scan[i].intensity >= 0.0F);
    REQUIRE(scan[i].intensity <= 1.0F);
  }
  CHECK(worst < 1e-4);  // float storage of points up to 120 m away
  CHECK(on_road > static_cast<int>(scan.size() / 3 / 4));
  // range limits hold
  for (const auto& p : scan) {
    const float r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    REQUIRE(r >= o.lidar.min_range - 1e-4);
    REQUIRE(r <= o.lidar.max_range + 1e-3);
  }
}

TEST_CASE("LiDAR: HDL-64E-like beams, range noise and dropout as asked") {
  const rgbl::SimLidarOptions lidar;
  const std::vector<double> e = lidar.elevations_deg();
  REQUIRE(e.size() == 64);
  CHECK_THAT(e.front(), WithinAbs(2.0, 1e-12));
  CHECK_THAT(e.back(), WithinAbs(-24.8, 1e-12));
  CHECK_THAT(e[0] - e[1], WithinAbs(1.0 / 3.0, 1e-9));  // upper block
  CHECK(e[40] - e[41] > 0.45);                            // lower block, sparser
  CHECK(std::is_sorted(e.rbegin(), e.rend()));

  rgbl::SyntheticOptions o = small_options();
  o.lidar.range_noise_sigma = 0.0;
  const auto exact = rgbl::SyntheticGenerator(o).render_scan(0);
  o.lidar.range_noise_sigma = 0.02;
  const auto noisy = rgbl::SyntheticGenerator(o).render_scan(0);
  REQUIRE(noisy.size() == exact.size());  // noise moves returns along their beams, never drops them
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const Eigen::Vector3f a(exact[i].x, exact[i].y, exact[i].z), b(noisy[i].x, noisy[i].y, noisy[i].z);
    REQUIRE(a.normalized().dot(b.normalized()) > 1.0F - 1e-6F);
    const double dr = b.norm() - a.norm();
    sum += dr;
    sum2 += dr * dr;
  }
  const double n = static_cast<double>(exact.size());
  CHECK_THAT(sum / n, WithinAbs(0.0, 1e-3));
  CHECK_THAT(std::sqrt(sum2 / n), WithinAbs(0.02, 0.001));

  o.lidar.dropout = 0.3;
  const auto sparse = rgbl::SyntheticGenerator(o).render_scan(0);
  CHECK_THAT(static_cast<double>(sparse.size()) / n, WithinAbs(0.7, 0.01));
}

TEST_CASE("LiDAR beams fire off their nominal elevations by the calibration error, the points keep the nominal ones") {
  rgbl::SyntheticOptions o = small_options();
  o.lidar.range_noise_sigma = 0.0;
  const std::vector<double> nominal = o.lidar.elevations_deg();
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  // A point as the beam really fired: its range along the nominal azimuth, at the nominal elevation
  // plus `error_deg`; on a surface of the scene when error_deg is the beam's true error.
  const auto fired_point = [](const rgbl::LidarPoint& p, double e_nominal, double error_deg) {
    const double r = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
    const double azimuth = std::atan2(double(p.y), double(p.x)), e = e_nominal + error_deg * kDeg;
    return Eigen::Vector3d(r * std::cos(e) * std::cos(azimuth), r * std::cos(e) * std::sin(azimuth), r * std::sin(e));
  };
  // The beam of a point: its elevation is the nominal one (the points are computed with it).
  const auto beam_of = [&](const rgbl::LidarPoint& p) {
    const double r = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
    const double e = std::asin(double(p.z) / r) / kDeg;
    std::size_t best = 0;
    for (std::size_t b = 1; b < nominal.size(); ++b) {
      if (std::abs(nominal[b] - e) < std::abs(nominal[best] - e)) best = b;
    }
    REQUIRE(std::abs(nominal[best] - e) < 1e-3);  // float storage
    return best;
  };
  // Each beam's error, recovered from the scan alone: the one that puts its points on the scene.
  const auto recovered_errors = [&](const rgbl::SyntheticGenerator& g, int frame) {
    const std::vector<rgbl::LidarPoint> scan = g.render_scan(frame);
    std::vector<std::vector<rgbl::LidarPoint>> beams(nominal.size());
    for (std::size_t i = 0; i < scan.size(); i += 7) {
      auto& beam = beams[beam_of(scan[i])];
      if (beam.size() < 12) beam.push_back(scan[i]);
    }
    const Eigen::Isometry3d T_world_lidar = g.pose(frame) * g.calibration().T_cam0_lidar;
    std::vector<double> errors;
    for (std::size_t b = 0; b < beams.size(); ++b) {
      if (beams[b].size() < 12) continue;
      const auto cost_of = [&](double error_deg) {
        double cost = 0.0;
        for (const auto& p : beams[b]) {
          cost += std::abs(g.scene().signed_distance(T_world_lidar * fired_point(p, nominal[b] * kDeg, error_deg)));
        }
        return cost;
      };
      // -0.6 .. 0.6 deg in steps of 0.01, then 0.001 around the best
      double best = 0.0, best_cost = 1e30;
      for (int k = -60; k <= 60; ++k) {
        if (const double cost = cost_of(k * 0.01); cost < best_cost) best_cost = cost, best = k * 0.01;
      }
      const double coarse = best;
      for (int k = -10; k <= 10; ++k) {
        if (const double cost = cost_of(coarse + k * 0.001); cost < best_cost) best_cost = cost, best = coarse + k * 0.001;
      }
      CHECK(best_cost / 12.0 < 2e-3);  // the beam's points lie on the scene again
      errors.push_back(best);
    }
    return errors;
  };

  SECTION("exact beams by default") {
    const rgbl::SyntheticGenerator g(o);
    const std::vector<double> errors = recovered_errors(g, 1);
    REQUIRE(errors.size() > 50);
    for (const double e : errors) CHECK_THAT(e, WithinAbs(0.0, 0.0015));
  }
  SECTION("an offset in all beams, and each beam's own error, the same in every frame") {
    o.lidar.elevation_offset_deg = 0.2;
    o.lidar.beam_elevation_sigma_deg = 0.1;
    const rgbl::SyntheticGenerator g(o);
    const std::vector<double> first = recovered_errors(g, 0), later = recovered_errors(g, 2);
    REQUIRE(first.size() > 50);
    REQUIRE(later.size() == first.size());
    double sum = 0.0, sum2 = 0.0;
    for (std::size_t b = 0; b < first.size(); ++b) {
      CHECK_THAT(later[b], WithinAbs(first[b], 0.0015));
      sum += first[b];
      sum2 += first[b] * first[b];
    }
    const double n = static_cast<double>(first.size()), mean = sum / n;
    const double sigma = std::sqrt(sum2 / n - mean * mean);
    CHECK_THAT(mean, WithinAbs(0.2, 0.04));   // 0.1 / sqrt(64) per beam draw: 3 sigmas
    CHECK(sigma > 0.07);
    CHECK(sigma < 0.13);
  }
}

TEST_CASE("projected noiseless LiDAR agrees with the exact depth image") {
  rgbl::SyntheticOptions o = small_options();
  o.width = 613;  // the default size: projection is pixel-exact only up to half a pixel
  o.height = 185;
  o.lidar.range_noise_sigma = 0.0;
  o.path.kind = rgbl::PathKind::curve;
  const rgbl::SyntheticGenerator g(o);
  const int frame = 2;
  const cv::Mat_<float> exact = g.render_depth(frame, 2);
  const auto scan = g.render_scan(frame);
  rgbl::ProjectionOptions po;
  po.min_depth = 1.0F;
  const cv::Mat_<float> sparse =
      rgbl::project_to_depth(scan, g.calibration().camera(2).P_img_lidar(), o.width, o.height, po);
  int projected = 0, close = 0, within_neighbourhood = 0;
  std::vector<double> errors;
  for (int v = 1; v < o.height - 1; ++v) {
    for (int u = 1; u < o.width - 1; ++u) {
      const float z = sparse(v, u);
      if (z == 0.0F) continue;
      ++projected;
      const double err = std::abs(z - exact(v, u));
      errors.push_back(err);
      close += err <= std::max(0.05, 0.01 * z) ? 1 : 0;
      // a LiDAR point lies up to half a pixel off the pixel centre: its depth is between the exact
      // depths of the pixel's neighbours
      float lo = 1e9F, hi = 0.0F;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const float e = exact(v + dv, u + du);
          if (e == 0.0F) continue;
          lo = std::min(lo, e);
          hi = std::max(hi, e);
        }
      within_neighbourhood += z >= lo - 0.02F && z <= hi + 0.02F ? 1 : 0;
    }
  }
  REQUIRE(projected > 3000);
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2), errors.end());
  INFO("projected " << projected << ", within 1%: " << close << ", within the 3x3 range: " << within_neighbourhood);
  CHECK(errors[errors.size() / 2] < 0.05);
  CHECK(static_cast<double>(within_neighbourhood) / projected > 0.99);
  CHECK(static_cast<double>(close) / projected > 0.8);
}

TEST_CASE("texture: ORB finds many corners all over the image, the untextured stretch is blank") {
  rgbl::SyntheticOptions o;  // default size
  o.frames = 12;
  o.untextured = rgbl::FrameRange{10, 11};
  const rgbl::SyntheticGenerator g(o);
  auto count_cells = [](const std::vector<cv::KeyPoint>& kps, int w, int h) {
    // a 4 x 2 grid over the image: how many cells hold at least 20 keypoints?
    std::array<int, 8> n{};
    for (const auto& k : kps) {
      const int cx = std::min(3, static_cast<int>(k.pt.x * 4 / w)), cy = std::min(1, static_cast<int>(k.pt.y * 2 / h));
      ++n[static_cast<std::size_t>(cy * 4 + cx)];
    }
    return static_cast<int>(std::count_if(n.begin(), n.end(), [](int c) { return c >= 20; }));
  };
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(2000, 1.2F, 8, 19, 0, 2, cv::ORB::HARRIS_SCORE, 31, 12);
  for (const int frame : {0, 5}) {
    for (const int camera : {0, 2}) {
      const cv::Mat image = g.render_image(frame, camera);
      std::vector<cv::KeyPoint> kps;
      orb->detect(image, kps);
      INFO("frame " << frame << " camera " << camera << ": " << kps.size() << " ORB keypoints");
      CHECK(kps.size() > 1200);
      CHECK(count_cells(kps, image.cols, image.rows) >= 7);
      cv::Mat grey = image;
      if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
      std::vector<cv::KeyPoint> fast;
      cv::FAST(grey, fast, 20);
      CHECK(fast.size() > 900);  // real KITTI 04 at this size: ~1600-1900
    }
  }
  // plain surfaces: only silhouettes are left
  const cv::Mat blank = g.render_image(10, 0);
  std::vector<cv::KeyPoint> fast;
  cv::FAST(blank, fast, 20);
  CHECK(fast.size() < 300);
  // the untextured stretch changes the look only: depth and scans are as before
  rgbl::SyntheticOptions textured = o;
  textured.untextured.reset();
  const rgbl::SyntheticGenerator t(textured);
  CHECK(same_bytes(g.render_depth(10, 2), t.render_depth(10, 2)));
  CHECK(same_scan(g.render_scan(10), t.render_scan(10)));
}

TEST_CASE("dropped scans are empty, their neighbours are not") {
  rgbl::SyntheticOptions o = small_options();
  o.dropped_scans = {1};
  const rgbl::SyntheticGenerator g(o);
  CHECK(g.render_scan(1).empty());
  CHECK(g.render_scan(0).size() > 80000);
  CHECK(g.render_scan(2).size() > 80000);
}

TEST_CASE("the last frame of a loop sees what the first saw") {
  rgbl::SyntheticOptions o = small_options();
  o.frames = 100;
  o.path.kind = rgbl::PathKind::loop;
  o.image_noise_sigma = 0.0;
  o.lidar.range_noise_sigma = 0.0;
  const rgbl::SyntheticGenerator g(o);
  CHECK(same_bytes(g.render_image(0, 0), g.render_image(99, 0)));
  CHECK(same_scan(g.render_scan(0), g.render_scan(99)));
  CHECK_FALSE(same_bytes(g.render_image(0, 0), g.render_image(50, 0)));
}

TEST_CASE("options validate and name the key") {
  auto key_of = [](const rgbl::SyntheticOptions& o) -> std::string {
    try {
      o.validate();
    } catch (const rgbl::ConfigError& e) {
      return e.key();
    }
    return "";
  };
  rgbl::SyntheticOptions o;
  CHECK(key_of(o).empty());
  auto bad = o;
  bad.frames = 0;
  CHECK(key_of(bad) == "frames");
  bad = o;
  bad.width = 8;
  CHECK(key_of(bad) == "width");
  bad = o;
  bad.depth_camera = 4;
  CHECK(key_of(bad) == "depth_camera");
  bad = o;
  bad.lidar.beams = 1;
  CHECK(key_of(bad) == "lidar.beams");
  bad = o;
  bad.lidar.dropout = 1.0;
  CHECK(key_of(bad) == "lidar.dropout");
  bad = o;
  bad.lidar.beam_elevation_sigma_deg = -0.1;
  CHECK(key_of(bad) == "lidar.beam_elevation_sigma_deg");
  bad = o;
  bad.lidar.elevation_offset_deg = 3.0;
  CHECK(key_of(bad) == "lidar.elevation_offset_deg");
  bad = o;
  bad.untextured = rgbl::FrameRange{5, 60};
  CHECK(key_of(bad) == "untextured");
  bad = o;
  bad.dropped_scans = {-1};
  CHECK(key_of(bad) == "dropped_scans");
  bad = o;
  bad.scene.sidewalk_width = 0.1;
  CHECK(key_of(bad) == "scene.sidewalk_width");
  bad = o;
  bad.speed = 0.0;
  CHECK(key_of(bad) == "speed");
  CHECK_THROWS_AS(rgbl::SyntheticGenerator(bad), rgbl::ConfigError);
}

TEST_CASE("the grey pair is rectified with the calibrated baseline: SGBM gives the exact depth") {
  rgbl::SyntheticOptions o;  // default size
  o.frames = 6;
  o.depth_camera = 0;
  const rgbl::SyntheticGenerator g(o);
  const cv::Mat left = g.render_image(5, 0), right = g.render_image(5, 1);
  const cv::Mat_<float> depth = g.render_depth(5, 0);
  const auto sgbm = cv::StereoSGBM::create(0, 64, 5, 8 * 25, 32 * 25, 1, 0, 10, 100, 2);
  cv::Mat disparity;
  sgbm->compute(left, right, disparity);
  const double bf = g.calibration().camera(0).camera.fx * g.calibration().baseline(0, 1);
  int with_depth = 0, valid = 0, good = 0;
  std::vector<double> rel;
  for (int v = 0; v < disparity.rows; ++v) {
    for (int u = 64; u < disparity.cols; ++u) {
      const float z = depth(v, u);
      if (z <= 0.0F || z > 60.0F) continue;
      ++with_depth;
      const auto d = disparity.at<std::int16_t>(v, u);
      if (d <= 0) continue;
      ++valid;
      const double e = std::abs(bf / (d / 16.0) - z) / z;
      rel.push_back(e);
      good += e < 0.05 ? 1 : 0;
    }
  }
  REQUIRE(valid > 0);
  std::nth_element(rel.begin(), rel.begin() + static_cast<std::ptrdiff_t>(rel.size() / 2), rel.end());
  INFO(valid << " of " << with_depth << " pixels matched, " << good << " within 5%");
  CHECK(static_cast<double>(valid) / with_depth > 0.85);
  CHECK(static_cast<double>(good) / valid > 0.7);
  CHECK(rel[rel.size() / 2] < 0.03);
}

TEST_CASE("a surface point looks the same from the next frame: ORB matches follow depth and poses") {
  rgbl::SyntheticOptions o;  // default size
  o.frames = 4;
  o.path.kind = rgbl::PathKind::curve;
  const rgbl::SyntheticGenerator g(o);
  const rgbl::CameraCalibration cal = g.calibration().camera(2);
  const cv::Mat a = g.render_image(2, 2), b = g.render_image(3, 2);
  const cv::Mat_<float> depth_a = g.render_depth(2, 2);
  const auto orb = cv::ORB::create(2000);
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  orb->detectAndCompute(a, cv::noArray(), ka, da);
  orb->detectAndCompute(b, cv::noArray(), kb, db);
  std::vector<cv::DMatch> matches;
  cv::BFMatcher(cv::NORM_HAMMING, true).match(da, db, matches);
  // where the exact depth and poses say each keypoint of frame 2 must appear in frame 3
  const Eigen::Isometry3d T_b_a = (g.pose(3) * cal.T_cam_cam0.inverse()).inverse() * (g.pose(2) * cal.T_cam_cam0.inverse());
  int checked = 0, consistent = 0;
  for (const auto& m : matches) {
    if (m.distance > 40) continue;
    const cv::Point2f pa = ka[static_cast<std::size_t>(m.queryIdx)].pt, pb = kb[static_cast<std::size_t>(m.trainIdx)].pt;
    const float z = depth_a(cvRound(pa.y), cvRound(pa.x));
    if (z <= 0.0F) continue;
    const Eigen::Vector3d p = T_b_a * cal.camera.unproject(Eigen::Vector2d(pa.x, pa.y), z);
    const Eigen::Vector2d predicted = cal.camera.project_unchecked(p);
    ++checked;
    consistent += (predicted - Eigen::Vector2d(pb.x, pb.y)).norm() < 3.0 ? 1 : 0;
  }
  INFO(consistent << " of " << checked << " good matches where depth and poses predict");
  CHECK(checked > 300);
  CHECK(static_cast<double>(consistent) / checked > 0.9);
}
