#include "rgbl/tracking/frame_motion.hpp"
#include "support/kitti_camera.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

namespace {

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

// A motion without rotation (T_cur_last: a camera driving d metres forward is shift(0, 0, -d)).
Eigen::Isometry3d shift(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double translation_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double rotation_error_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle() * 180.0 / 3.14159265358979;
}

// A motion found, and the true one to a millimetre and a thousandth of a degree.
void check_exact(const std::optional<Eigen::Isometry3d>& T, const Eigen::Isometry3d& truth) {
  REQUIRE(T);
  CHECK(translation_error(*T, truth) < 1e-3);
  CHECK(rotation_error_deg(*T, truth) < 1e-3);
}

}  // namespace

TEST_CASE("frame motion: a van ahead at the camera's speed holds most matches, coverage and the prior keep the scene") {
  const rgbl::PinholeCamera cam = rgbl::test::kitti_camera();
  std::mt19937 rng(11);
  // The car drives 1.4 m forward and yaws 0.5 deg; a van 12-16 m ahead moves exactly with it, so its
  // points stay put in the camera frame. 90 van points against 60 of the static scene, which spread
  // over much more of the image.
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.linear() = Eigen::AngleAxisd(0.5 * 3.14159265358979 / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_true.translation() = Eigen::Vector3d(0.02, 0.0, -1.4);
  Scene scene;
  add_points(scene, rng, 60, {-5.0, -1.5, 8.0}, {5.0, 1.5, 45.0}, T_true);  // all in view
  add_points(scene, rng, 90, {-1.2, -1.5, 12.0}, {1.2, 1.0, 16.0}, Eigen::Isometry3d::Identity());
  const auto [last, cur] = frames_of(scene, cam, rng);
  rgbl::TrackerOptions options;
  rgbl::TrackerOptions by_size = options;
  by_size.ransac_coverage_cell = 0.0;  // rank a consensus by its size only
  Eigen::Isometry3d prior = T_true;  // a constant-velocity prior 0.25 m and 1 deg off
  prior.translation() += Eigen::Vector3d(0.1, -0.05, 0.22);
  prior.linear() = Eigen::AngleAxisd(1.0 * 3.14159265358979 / 180.0, Eigen::Vector3d::UnitX()) * prior.linear();

  SECTION("ranked by size, without a prior, the largest consensus wins: the van (no motion)") {
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, by_size);
    REQUIRE(T);
    CHECK(translation_error(*T, Eigen::Isometry3d::Identity()) < 1e-3);
  }
  SECTION("ranked by image coverage, without a prior: the static scene's motion, exactly") {
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options);
    check_exact(T, T_true);
  }
  SECTION("ranked by size, with the prior: the static scene's motion, exactly") {
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, by_size, prior);
    check_exact(T, T_true);
  }
  SECTION("a prior far from every consensus: no prediction rather than a jump to the van") {
    Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
    far.translation() = Eigen::Vector3d(0.0, 0.0, -3.5);  // window: 0.3 + 0.25 * 3.5 = 1.175 m
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, options, far));
  }
  SECTION("too few static points near the prior: no prediction") {
    by_size.ransac_min_inliers = 70;  // the scene has 60, the van 90
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, by_size, prior));
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, by_size);
    REQUIRE(T);
    CHECK(translation_error(*T, Eigen::Isometry3d::Identity()) < 1e-3);
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

TEST_CASE("frame motion: a truck alongside at the camera's speed covers more of the image, the road decides") {
  const rgbl::PinholeCamera cam = rgbl::test::kitti_camera();
  std::mt19937 rng(5);
  // The camera (1.65 m above the road, y down) drives 1.0 m forward. A truck's side 2.5 m to the right
  // moves exactly with it and fills the right half of the image; the static scene is the road ahead
  // and a few facades far on the left.
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.translation() = Eigen::Vector3d(0.0, 0.0, -1.0);
  Scene scene;
  add_points(scene, rng, 40, {-3.0, 1.65, 6.0}, {1.5, 1.65, 25.0}, T_true);    // road
  add_points(scene, rng, 12, {-9.0, -4.0, 25.0}, {-8.0, 1.0, 45.0}, T_true);   // facades
  add_points(scene, rng, 160, {2.5, -2.6, 3.2}, {2.5, 1.3, 14.0}, Eigen::Isometry3d::Identity());  // truck side
  auto [last, cur] = frames_of(scene, cam, rng);
  cur.build_grid(cam.width, cam.height);
  rgbl::TrackerOptions options;
  rgbl::TrackerOptions coverage_only = options;
  coverage_only.ransac_ground_first = false;

  SECTION("ranked by image coverage alone, the truck wins (no motion)") {
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, coverage_only);
    REQUIRE(T);
    // the far facades agree with both motions (3 % of 45 m), so the consensus leans a little off zero
    CHECK(translation_error(*T, Eigen::Isometry3d::Identity()) < 0.2);
    CHECK(translation_error(*T, T_true) > 0.8);
  }
  SECTION("ground cells first: the scene's motion, exactly, and the truck's points labelled moving") {
    std::vector<bool> moving;
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options, std::nullopt, &moving);
    check_exact(T, T_true);
    REQUIRE(moving.size() == cur.size());
    int truck = 0, truck_moving = 0, scene_moving = 0;
    for (std::size_t i = 0; i < cur.size(); ++i) {
      // the truck side is the only surface at x = 2.5 m
      const bool on_truck = std::abs(cam.unproject({cur.keypoints[i].x, cur.keypoints[i].y}, cur.depth[i]).x() - 2.5) < 1e-3;
      truck += on_truck ? 1 : 0;
      truck_moving += on_truck && moving[i] ? 1 : 0;
      scene_moving += !on_truck && moving[i] ? 1 : 0;
    }
    CHECK(truck == 160);
    CHECK(truck_moving == truck);
    CHECK(scene_moving == 0);
  }
  SECTION("coverage alone picks the truck; the rival is the scene's motion, exactly, with its own labels") {
    std::vector<bool> moving;
    std::optional<rgbl::RivalMotion> rival;
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, coverage_only, std::nullopt, &moving, &rival);
    REQUIRE(T);
    CHECK(translation_error(*T, T_true) > 0.8);
    REQUIRE(rival);
    CHECK(translation_error(rival->T_cur_last, T_true) < 1e-3);
    CHECK(rotation_error_deg(rival->T_cur_last, T_true) < 1e-3);
    // the road points and the facades the winner did not take (some facades agree with both)
    CHECK(rival->inliers >= 40);
    CHECK(rival->inliers <= 52);
    REQUIRE(rival->moving.size() == cur.size());
    int truck_moving = 0;
    for (std::size_t i = 0; i < cur.size(); ++i) {
      const bool on_truck = std::abs(cam.unproject({cur.keypoints[i].x, cur.keypoints[i].y}, cur.depth[i]).x() - 2.5) < 1e-3;
      truck_moving += on_truck && rival->moving[i] ? 1 : 0;
    }
    CHECK(truck_moving == 160);
  }
  SECTION("with a prior there is no rival: the prior already chose") {
    std::optional<rgbl::RivalMotion> rival;
    REQUIRE(rgbl::estimate_frame_motion(cam, last, cur, options, T_true, nullptr, &rival));
    CHECK_FALSE(rival);
  }
  SECTION("the road's keypoints: all 40 and nothing else") {
    const std::vector<bool> ground = rgbl::ground_keypoints(cam, cur, options);
    REQUIRE(ground.size() == cur.size());
    int road = 0, other = 0;
    for (std::size_t i = 0; i < cur.size(); ++i) {
      const bool on_road = std::abs(cam.unproject({cur.keypoints[i].x, cur.keypoints[i].y}, cur.depth[i]).y() - 1.65) < 1e-3;
      road += on_road && ground[i] ? 1 : 0;
      other += !on_road && ground[i] ? 1 : 0;
    }
    CHECK(road == 40);
    CHECK(other == 0);
    rgbl::TrackerOptions strict = options;
    strict.ground_min_points = 60;
    CHECK(rgbl::ground_keypoints(cam, cur, strict).empty());
  }
  SECTION("without a road plane (too few points on it) coverage decides again") {
    rgbl::TrackerOptions strict = options;
    strict.ground_min_points = 60;
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, strict);
    REQUIRE(T);
    CHECK(translation_error(*T, T_true) > 0.8);
  }
}

TEST_CASE("road start: vehicles in both directions hold the subset's matches, the road's keypoints the motion") {
  const rgbl::PinholeCamera cam = rgbl::test::kitti_camera();
  std::mt19937 rng(9);
  // The camera drives 1.0 m forward between a truck alongside at its speed (right) and an oncoming lane
  // closing at 1.2 m a frame (left); 30 road points ahead are the only static scene. The RANSAC's subset
  // of ransac_max_points (a stride over all 2030 keypoints) keeps about 5 of them, fewer than a guess needs.
  const Eigen::Isometry3d T_true = shift(0.0, 0.0, -1.0);
  const Eigen::Isometry3d T_oncoming = shift(0.0, 0.0, -2.2);
  Scene scene;
  add_points(scene, rng, 30, {-1.5, 1.65, 6.0}, {1.5, 1.65, 16.0}, T_true);                          // road
  // the vehicles' bodies end 0.85 m above the road: lower, far points would pass as road within the
  // depth-relative tolerance of the ground test (ransac_relative_tolerance * z)
  add_points(scene, rng, 1000, {2.5, -2.6, 3.2}, {2.5, 0.8, 16.0}, Eigen::Isometry3d::Identity());   // truck side
  add_points(scene, rng, 1000, {-3.5, -2.0, 8.0}, {-3.5, 0.8, 20.0}, T_oncoming);                     // oncoming
  auto [last, cur] = frames_of(scene, cam, rng);
  cur.build_grid(cam.width, cam.height);
  rgbl::TrackerOptions options;
  rgbl::TrackerOptions guess = options;
  guess.ransac_min_inliers = options.ransac_guess_min_inliers;

  SECTION("all keypoints: a vehicle's motion") {
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, guess);
    REQUIRE(T);
    CHECK(translation_error(*T, T_true) > 0.8);
  }
  SECTION("the road's keypoints alone: the camera's motion, exactly") {
    const auto T = rgbl::estimate_road_motion(cam, last, cur, options);
    check_exact(T, T_true);
  }
  SECTION("fewer road keypoints than a guess needs: no start") {
    rgbl::TrackerOptions strict = options;
    strict.ransac_guess_min_inliers = 31;
    CHECK_FALSE(rgbl::estimate_road_motion(cam, last, cur, strict));
  }
  SECTION("no road plane in a frame: no start") {
    rgbl::TrackerOptions strict = options;
    strict.ground_min_points = 40;
    CHECK_FALSE(rgbl::estimate_road_motion(cam, last, cur, strict));
  }
}

TEST_CASE("frame motion: ground and moving-object options are validated with their keys") {
  rgbl::TrackerOptions options;
  options.ground_max_tilt_deg = 95.0;
  CHECK_THROWS_WITH(options.validate(), Catch::Matchers::Contains("tracker.ground_max_tilt_deg"));
  options = {};
  options.ground_min_points = 2;
  CHECK_THROWS_WITH(options.validate(), Catch::Matchers::Contains("tracker.ground_min_points"));
  options = {};
  options.motion_gate_factor = -1.0;
  CHECK_THROWS_WITH(options.validate(), Catch::Matchers::Contains("tracker.motion_gate_factor"));
  options = {};
  options.moving_label_radius = -1.0;
  CHECK_THROWS_WITH(options.validate(), Catch::Matchers::Contains("tracker.moving_label_radius"));
}

TEST_CASE("scan evidence: the road's returns leave, the rest counts once per voxel") {
  // Camera frame (y down): a road 1.65 m below the camera sampled every 10 cm, and a pole 5 m to the
  // right sampled every 1 cm (a near object returns far more points per square metre than a far one).
  rgbl::ScanSample sample;
  for (double x = -8.0; x <= 8.0; x += 0.1) {
    for (double z = 3.0; z <= 30.0; z += 0.1) sample.points.emplace_back(x, 1.65, z);
  }
  const std::size_t road = sample.points.size();
  for (double y = -3.0; y < 1.0; y += 0.01) sample.points.emplace_back(5.0, y, 10.0);
  const rgbl::TrackerOptions options;  // scan_sample.tolerance 0.3 m
  const rgbl::ScanSample evidence = rgbl::scan_evidence(sample, options);
  // no road return is left; the pole's 400 returns become one per 0.3 m voxel it crosses (4 m / 0.3)
  for (const Eigen::Vector3f& p : evidence.points) CHECK(p.x() == Approx(5.0F));
  CHECK(evidence.points.size() >= 13);
  CHECK(evidence.points.size() <= 15);
  CHECK(road > 40000);

  // without a ground plane (too few points below the camera) nothing is taken for road
  rgbl::ScanSample wall;
  for (double y = -3.0; y < 0.5; y += 0.01) wall.points.emplace_back(0.0, y, 10.0);
  CHECK(rgbl::scan_evidence(wall, options).points.size() >= 11);
}

TEST_CASE("road plane: the least-squares plane of the road's returns, the camera's height and tilt") {
  // Camera frame (y down): a road 1.65 m below the camera, pitched 2 deg (it rises ahead), every 10 cm,
  // with a pole and a wall off it that must not bend the fit.
  const double pitch = 2.0 * M_PI / 180.0;
  const Eigen::Vector3d n(0.0, std::cos(pitch), std::sin(pitch));  // pointing down, tilted forward
  rgbl::ScanSample sample;
  for (double x = -8.0; x <= 8.0; x += 0.1) {
    for (double z = 3.0; z <= 30.0; z += 0.1) {
      // the point (x, y, z) with n . p = 1.65
      const double y = (1.65 - n.z() * z) / n.y();
      sample.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    }
  }
  for (double y = -3.0; y < 1.0; y += 0.01) sample.points.emplace_back(5.0F, static_cast<float>(y), 10.0F);
  for (double x = -8.0; x <= 8.0; x += 0.05) {
    for (double y = -3.0; y < 0.5; y += 0.05) sample.points.emplace_back(static_cast<float>(x), static_cast<float>(y), 35.0F);
  }
  const rgbl::TrackerOptions options;
  const std::optional<rgbl::RoadPlane> road = rgbl::road_plane(sample, options);
  REQUIRE(road);
  CHECK(road->n.dot(n) == Approx(1.0).margin(1e-9));  // float coordinates: ~1e-7 m of noise
  CHECK(road->d == Approx(1.65).margin(1e-5));
  // every return of the road up to where it rises to ground_min_height (0.8 m) below the camera:
  // 161 across, z = 3 .. 24.3 m (214 rows)
  CHECK(road->points == Approx(161 * 214).margin(161));
  // a scan without a road under the camera has none
  rgbl::ScanSample wall;
  for (double y = -3.0; y < 0.5; y += 0.01) wall.points.emplace_back(0.0F, static_cast<float>(y), 10.0F);
  CHECK_FALSE(rgbl::road_plane(wall, options));
}

TEST_CASE("frame motion: near a prior with every keypoint with depth, a scene in few matches is found") {
  // Vehicles hide most of the scene (traffic seed 7 of the simulator): of ~700 keypoints with depth per
  // frame only 40 match the last frame's on the static scene. A strided subset of 350 keeps about half
  // of those, short of ransac_min_inliers (30), and gives no prediction alone; the second RANSAC on up
  // to 1000 (ransac_max_points_near_prior_retry, opt-in) or ransac_max_points_near_prior 1000 (opt-in,
  // every frame) takes them all.
  const rgbl::PinholeCamera cam = rgbl::test::kitti_camera();
  std::mt19937 rng(5);
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.translation() = Eigen::Vector3d(0.0, 0.0, -1.0);
  Scene scene;
  add_points(scene, rng, 40, {-6.0, -1.5, 8.0}, {6.0, 1.5, 40.0}, T_true);
  auto [last, cur] = frames_of(scene, cam, rng);
  // 660 keypoints with depth in each frame that match nothing (random descriptors: ~128 bits apart)
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> byte(0, 255);
  for (rgbl::Frame* f : {&last, &cur}) {
    for (int k = 0; k < 660; ++k) {
      const Eigen::Vector3d p(-6.0 + 12.0 * u(rng), -1.5 + 3.0 * u(rng), 8.0 + 32.0 * u(rng));
      const Eigen::Vector2d px = cam.project_unchecked(p);
      rgbl::Keypoint kp;
      kp.x = static_cast<float>(px.x());
      kp.y = static_cast<float>(px.y());
      rgbl::Descriptor d;
      for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
      // interleaved with the scene's keypoints, as a detector lists them (by image cell)
      const auto at = static_cast<std::ptrdiff_t>(rng() % (f->keypoints.size() + 1));
      f->keypoints.insert(f->keypoints.begin() + at, kp);
      f->descriptors.insert(f->descriptors.begin() + at, d);
      f->depth.insert(f->depth.begin() + at, static_cast<float>(p.z()));
      f->depth_sigma.insert(f->depth_sigma.begin() + at, 0.1F);
    }
  }
  REQUIRE(cur.size() == 700);
  Eigen::Isometry3d prior = T_true;  // the constant-velocity prior, 0.1 m off
  prior.translation() += Eigen::Vector3d(0.05, 0.0, 0.08);
  rgbl::TrackerOptions options;
  REQUIRE(options.ransac_min_inliers == 30);
  REQUIRE(options.ransac_max_points == 350);
  SECTION("near the prior with every keypoint (Tracking.RansacPointsNearPrior: 1000): the scene's motion, exactly") {
    options.ransac_max_points_near_prior = 1000;
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options, prior);
    check_exact(T, T_true);
  }
  SECTION("a subset of 350 alone (the default: no second RANSAC) keeps too few of the scene's matches: no prediction") {
    REQUIRE(options.ransac_max_points_near_prior == 350);
    REQUIRE(options.ransac_max_points_near_prior_retry == 0);
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, options, prior));
  }
  SECTION("the subset of 350 first, every keypoint again when it finds too few (opt-in): the scene's motion, exactly") {
    options.ransac_max_points_near_prior_retry = 1000;
    std::vector<bool> moving;
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options, prior, &moving);
    check_exact(T, T_true);
    CHECK(moving.size() == cur.size());
  }
  SECTION("the second RANSAC is near a prior only: without one the subset's verdict stands") {
    options.ransac_max_points_near_prior_retry = 1000;
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, options));
  }
  SECTION("without a prior the subset is ransac_max_points' however many near a prior") {
    options.ransac_max_points_near_prior = 1000;
    CHECK_FALSE(rgbl::estimate_frame_motion(cam, last, cur, options));
    options.ransac_max_points = 1000;
    const auto T = rgbl::estimate_frame_motion(cam, last, cur, options);
    REQUIRE(T);
    CHECK(translation_error(*T, T_true) < 1e-3);
  }
}

TEST_CASE("rays without depth: the scene beyond the LiDAR tells a driving camera from one standing among vehicles") {
  const rgbl::PinholeCamera cam = rgbl::test::kitti_camera();
  std::mt19937 rng(5);
  // The car drives 1.0 m forward. Without depth: 150 facade points 11-16 m ahead on both sides, 60
  // points on a truck's top alongside that moves with the car (they stay put in the image), 30 points
  // near infinity (they fit any translation). All in view in both frames, as keypoints are.
  const Eigen::Isometry3d T_drive = shift(0.0, 0.0, -1.0);
  const Eigen::Isometry3d T_side = shift(1.0, 0.0, 0.0);
  const Eigen::Isometry3d T_stand = Eigen::Isometry3d::Identity();
  Scene s;
  add_points(s, rng, 75, {-8.0, -2.2, 11.0}, {-6.0, -1.2, 16.0}, T_drive);
  add_points(s, rng, 75, {6.0, -2.2, 11.0}, {8.0, -1.2, 16.0}, T_drive);
  add_points(s, rng, 60, {2.5, -1.5, 6.0}, {4.0, -0.8, 14.0}, T_stand);
  add_points(s, rng, 30, {-400.0, -200.0, 3000.0}, {400.0, -50.0, 4000.0}, T_drive);
  auto [last, cur] = frames_of(s, cam, rng);
  for (const rgbl::Frame* f : {&last, &cur}) {
    for (const rgbl::Keypoint& k : f->keypoints) REQUIRE((k.x >= 0.0F && k.x < cam.width && k.y >= 0.0F && k.y < cam.height));
  }
  std::fill(last.depth.begin(), last.depth.end(), 0.0F);
  std::fill(last.depth_sigma.begin(), last.depth_sigma.end(), 0.0F);

  const rgbl::RayFits drive_or_stand = rgbl::fits_by_rays(cam, last, cur, T_drive, T_stand, 100, 1.2);
  CHECK(drive_or_stand.matches == 240);
  CHECK(drive_or_stand.a_only >= 140);  // the facades' parallax; the truck and the far points fit both
  CHECK(drive_or_stand.b_only == 0);
  const rgbl::RayFits stand_or_drive = rgbl::fits_by_rays(cam, last, cur, T_stand, T_drive, 100, 1.2);
  CHECK(stand_or_drive.a_only == drive_or_stand.b_only);
  CHECK(stand_or_drive.b_only == drive_or_stand.a_only);
  // sideways is no forward step either: the facades fit the true motion alone
  const rgbl::RayFits drive_or_side = rgbl::fits_by_rays(cam, last, cur, T_drive, T_side, 100, 1.2);
  CHECK(drive_or_side.a_only >= 120);
  CHECK(drive_or_side.b_only <= 5);
  // keypoints with depth are not asked: the LiDAR decides those
  std::fill(last.depth.begin(), last.depth.end(), 12.0F);
  CHECK(rgbl::fits_by_rays(cam, last, cur, T_drive, T_stand, 100, 1.2).matches == 0);
}
