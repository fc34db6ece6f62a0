#include "rgbl/tracking/frame_motion.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <random>
#include <vector>

namespace {

rgbl::PinholeCamera kitti_like_camera() {
  rgbl::PinholeCamera cam;
  cam.fx = cam.fy = 707.0;
  cam.cx = 601.9;
  cam.cy = 183.1;
  cam.width = 1226;
  cam.height = 370;
  return cam;
}

struct Scene {
  std::vector<Eigen::Vector3d> points_last;  // last camera frame
  std::vector<Eigen::Vector3d> points_cur;   // current camera frame
};

// Adds n points in the box [lo, hi] (last camera frame) that move rigidly by T_cur_last.
void add_points(Scene& s, std::mt19937& rng, int n, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                const Eigen::Isometry3d& T_cur_last) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(lo.x() + u(rng) * (hi.x() - lo.x()), lo.y() + u(rng) * (hi.y() - lo.y()),
                            lo.z() + u(rng) * (hi.z() - lo.z()));
    s.points_last.push_back(p);
    s.points_cur.push_back(T_cur_last * p);
  }
}

// Point k gets the same random descriptor in both frames; the current frame lists them in another order.
std::pair<rgbl::Frame, rgbl::Frame> frames_of(const Scene& s, const rgbl::PinholeCamera& cam, std::mt19937& rng) {
  const std::size_t n = s.points_last.size();
  std::vector<rgbl::Descriptor> descriptors(n);
  std::uniform_int_distribution<int> byte(0, 255);
  for (auto& d : descriptors)
    for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
  std::vector<std::size_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), rng);
  auto make = [&](const std::vector<Eigen::Vector3d>& points, bool shuffled) {
    rgbl::Frame f;
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t k = shuffled ? order[j] : j;
      const Eigen::Vector2d px = cam.project_unchecked(points[k]);
      rgbl::Keypoint kp;
      kp.x = static_cast<float>(px.x());
      kp.y = static_cast<float>(px.y());
      f.keypoints.push_back(kp);
      f.descriptors.push_back(descriptors[k]);
      f.depth.push_back(static_cast<float>(points[k].z()));
      f.depth_sigma.push_back(0.1F);
    }
    return f;
  };
  return {make(s.points_last, false), make(s.points_cur, true)};
}

double translation_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double rotation_error_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle() * 180.0 / 3.14159265358979;
}

}  // namespace

TEST_CASE("frame motion: a van ahead at the camera's speed outnumbers the static scene; the prior keeps the scene") {
  const rgbl::PinholeCamera cam = kitti_like_camera();
  std::mt19937 rng(11);
  // The car drives 1.4 m forward and yaws 0.5 deg; a van 12-16 m ahead moves exactly with it, so its
  // points stay put in the camera frame. 90 van points against 45 of the static scene.
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.linear() = Eigen::AngleAxisd(0.5 * 3.14159265358979 / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_true.translation() = Eigen::Vector3d(0.02, 0.0, -1.4);
  Scene scene;
  add_points(scene, rng, 45, {-5.0, -1.5, 8.0}, {5.0, 1.5, 45.0}, T_true);  // all in view
  add_points(scene, rng, 90, {-1.2, -1.5, 12.0}, {1.2, 1.0, 16.0}, Eigen::Isometry3d::Identity());
  const auto [last, cur] = frames_of(scene, cam, rng);
  rgbl::TrackerOptions options;

  SECTION("without a prior the largest consensus wins: the van (no motion)") {
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options);
    REQUIRE(T);
    CHECK(translation_error(*T, Eigen::Isometry3d::Identity()) < 1e-3);
  }
  SECTION("a constant-velocity prior 0.25 m and 1 deg off: the static scene's motion, exactly") {
    Eigen::Isometry3d prior = T_true;
    prior.translation() += Eigen::Vector3d(0.1, -0.05, 0.22);
    prior.linear() = Eigen::AngleAxisd(1.0 * 3.14159265358979 / 180.0, Eigen::Vector3d::UnitX()) * prior.linear();
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options, prior);
    REQUIRE(T);
    CHECK(translation_error(*T, T_true) < 1e-3);
    CHECK(rotation_error_deg(*T, T_true) < 1e-3);
  }
  SECTION("a prior far from every consensus: no prediction rather than a jump to the van") {
    Eigen::Isometry3d prior = Eigen::Isometry3d::Identity();
    prior.translation() = Eigen::Vector3d(0.0, 0.0, -3.5);  // window: 0.3 + 0.25 * 3.5 = 1.175 m
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, options, prior));
  }
  SECTION("too few static points near the prior: no prediction") {
    options.ransac_min_inliers = 50;  // the scene has 45
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, options, T_true));
    CHECK(rgbl::estimate_frame_motion(cam, last, cur, options));  // the van's 90 still agree
  }
}

TEST_CASE("frame motion: options are validated with their keys") {
  rgbl::TrackerOptions options;
  options.ransac_prior_rotation_deg = -1.0;
  CHECK_THROWS_WITH(options.validate(), Catch::Matchers::Contains("tracker.ransac_prior_rotation_deg"));
  options = {};
  options.ransac_min_inliers = 2;
  CHECK_THROWS_WITH(options.validate(), Catch::Matchers::Contains("tracker.ransac_min_inliers"));
}
