// The stress scenarios: each produces what it claims, checked against the exact geometry.
#include "rgbl/core/error.hpp"
#include "rgbl/geometry/scan_registration.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/sim/scenarios.hpp"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>

using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double heading(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d f = T.linear().col(2);
  return std::atan2(f.x(), f.z());
}

// World ray of camera 0's pixel (u, v) at a frame: origin and direction with camera z = 1.
struct Ray {
  Eigen::Vector3d origin, direction;
};

Ray pixel_ray(const rgbl::SyntheticGenerator& g, int frame, double u, double v) {
  const rgbl::PinholeCamera& cam = g.calibration().camera(0).camera;
  const Eigen::Isometry3d T = g.pose(frame);
  return {T.translation(), T.linear() * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0)};
}

bool is_actor(const rgbl::SyntheticGenerator& g, const rgbl::RayHit& hit) {
  return hit.object != rgbl::StreetScene::kGround && hit.object >= g.scene().objects().size();
}

// Share of camera 0's pixels whose centre ray first hits an actor.
double actor_share(const rgbl::SyntheticGenerator& g, int frame) {
  const rgbl::PinholeCamera& cam = g.calibration().camera(0).camera;
  int hits = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Ray r = pixel_ray(g, frame, u, v);
      const auto hit = g.intersect(frame, r.origin, r.direction, 500.0);
      if (hit && is_actor(g, *hit)) ++hits;
    }
  }
  return static_cast<double>(hits) / (cam.width * cam.height);
}

// Signed distance of a world point to one upright box (independent of the ray caster).
double box_distance(const rgbl::SceneObject& o, const Eigen::Vector3d& p) {
  const double rx = p.x() - o.cx, rz = p.z() - o.cz;
  const double qx = std::abs(rx * o.ax + rz * o.az) - o.hx, qy = std::abs(p.y() - o.cy) - o.hy;
  const double qz = std::abs(-rx * o.az + rz * o.ax) - o.hz;
  const Eigen::Vector3d outside(std::max(qx, 0.0), std::max(qy, 0.0), std::max(qz, 0.0));
  return outside.norm() + std::min(std::max({qx, qy, qz}), 0.0);
}

// LiDAR returns (noise off) against the exact geometry: each return's range is that of the first
// surface along its beam (the beam re-derived from the stored float point may graze another surface
// at a silhouette: allowed for 0.5 % of the returns), and a return on an actor lies on one of its
// boxes. Returns how many returns hit actors.
int check_actor_returns(const rgbl::SyntheticGenerator& g, int frame) {
  const Eigen::Isometry3d T = g.pose(frame) * g.calibration().T_cam0_lidar;
  const std::vector<rgbl::SceneObject> boxes = g.actor_boxes(frame);
  const std::vector<rgbl::LidarPoint> scan = g.render_scan(frame);
  int on_actors = 0, off = 0, not_on_box = 0;
  for (const rgbl::LidarPoint& p : scan) {
    const Eigen::Vector3d local(p.x, p.y, p.z);
    const double range = local.norm();
    const auto hit = g.intersect(frame, T.translation(), T.linear() * local / range, 200.0);
    if (!hit || std::abs(range - hit->t) > 1e-4 * std::max(1.0, hit->t)) {  // float storage
      ++off;
      continue;
    }
    if (!is_actor(g, *hit)) continue;
    ++on_actors;
    const Eigen::Vector3d w = T * local;
    double nearest = 1e9;
    for (const auto& b : boxes) nearest = std::min(nearest, std::abs(box_distance(b, w)));
    if (nearest > 1e-4 * std::max(1.0, range)) ++not_on_box;
  }
  CHECK(off < 0.005 * static_cast<double>(scan.size()));
  CHECK(not_on_box == 0);
  return on_actors;
}

}  // namespace

TEST_CASE("the scenario registry lists every scenario, each with its options and a default length >= 60") {
  const auto list = rgbl::scenarios();
  std::set<std::string> names;
  for (const auto& s : list) {
    names.insert(std::string(s.name));
    CHECK(s.default_frames >= 60);
    CHECK_FALSE(s.description.empty());
    const rgbl::SyntheticOptions o = rgbl::scenario_options(s.name, 3);
    CHECK(o.frames == s.default_frames);
    CHECK(o.seed == 3);
    CHECK(o.scenario == s.name);
    CHECK(rgbl::scenario_options(s.name, 3, 20).frames == 20);
  }
  CHECK(list.front().name == "plain");
  for (const char* required : {"plain", "lead-vehicle", "traffic", "foliage", "shadows", "turn", "suburban", "repeated"}) {
    CHECK(names.count(required) == 1);
  }
  try {
    (void)rgbl::scenario_options("no-such", 1);
    FAIL("an unknown scenario was accepted");
  } catch (const rgbl::ConfigError& e) {
    CHECK(e.key() == "scenario");
    CHECK_THAT(std::string(e.what()), Contains("lead-vehicle"));
  }
}

TEST_CASE("speed profiles: exact distances, an exact standstill, no negative speed") {
  const rgbl::SpeedProfile p(10.0, {{2.0, 0.0}, {4.0, -2.5}, {1.0, 0.0}, {2.0, 1.0}});
  CHECK(p.distance(1.0) == 10.0);
  CHECK_THAT(p.distance(4.0), WithinAbs(20.0 + 10.0 * 2.0 - 0.5 * 2.5 * 4.0, 1e-12));
  CHECK(p.speed(6.0) == 0.0);
  CHECK(p.distance(6.0) == p.distance(6.9));  // standing still, to the bit
  CHECK_THAT(p.speed(8.0), WithinAbs(1.0, 1e-12));
  CHECK_THAT(p.speed(20.0), WithinAbs(2.0, 1e-12));
  CHECK_THROWS_AS(rgbl::SpeedProfile(5.0, {{3.0, -2.0}}), rgbl::ConfigError);
  rgbl::SyntheticOptions o;
  o.speed_phases = {{1.0, -20.0}};
  CHECK_THROWS_WITH(o.validate(), Contains("speed_phases"));
}

TEST_CASE("lead-vehicle: a van ahead at the ego speed covers 10-25 % of the image for the whole run") {
  rgbl::SyntheticOptions o = rgbl::scenario_options("lead-vehicle", 1);
  o.lidar.range_noise_sigma = 0.0;
  const rgbl::SyntheticGenerator g(o);
  REQUIRE(o.actors.size() == 1);
  for (const int f : {0, 15, 30, 45, o.frames - 1}) {
    const double share = actor_share(g, f);
    INFO("frame " << f << ": share " << share);
    CHECK(share >= 0.10);
    CHECK(share <= 0.25);
  }
  // on the straight, the van's back is exactly its gap ahead: the depth of the image centre
  const rgbl::PinholeCamera& cam = g.calibration().camera(0).camera;
  const double gap = o.actors[0].s0 - 0.5 * o.actors[0].length();
  const cv::Mat_<float> depth = g.render_depth(10, 0);
  CHECK_THAT(depth(static_cast<int>(std::lround(cam.cy)), static_cast<int>(std::lround(cam.cx))), WithinAbs(gap, 1e-4));
  CHECK(check_actor_returns(g, 10) > 500);
}

TEST_CASE("traffic: the ego brakes to a standstill of >= 10 frames while the others keep moving") {
  rgbl::SyntheticOptions o = rgbl::scenario_options("traffic", 2);
  o.lidar.range_noise_sigma = 0.0;
  const rgbl::SyntheticGenerator g(o);
  int longest = 0, run = 0, first_still = -1;
  for (int f = 1; f < o.frames; ++f) {
    const bool still = g.pose(f).matrix() == g.pose(f - 1).matrix();
    run = still ? run + 1 : 0;
    if (still && first_still < 0) first_still = f - 1;
    longest = std::max(longest, run + 1);
  }
  CHECK(longest >= 10);
  REQUIRE(first_still > 0);
  // braking at 3.5 m/s^2 before the stop: the steps shrink by 0.035 m per frame
  const double a = g.arc_length(first_still - 5) - 2.0 * g.arc_length(first_still - 6) + g.arc_length(first_still - 7);
  CHECK_THAT(a / (o.frame_period * o.frame_period), WithinAbs(-3.5, 1e-6));
  // both directions, trucks among them, every actor moving while the ego stands
  bool oncoming = false, along = false;
  for (const auto& actor : o.actors) (actor.oncoming ? oncoming : along) = true;
  CHECK(oncoming);
  CHECK(along);
  const auto b0 = g.actor_boxes(first_still), b1 = g.actor_boxes(first_still + 5);
  REQUIRE(b0.size() == b1.size());
  for (std::size_t k = 0; k < b0.size(); ++k) CHECK(std::hypot(b1[k].cx - b0[k].cx, b1[k].cz - b0[k].cz) > 2.0);
  // and they are in view: the standing camera's depth image changes
  const cv::Mat_<float> d0 = g.render_depth(first_still, 0), d1 = g.render_depth(first_still + 5, 0);
  CHECK(cv::countNonZero(cv::abs(d0 - d1) > 0.5F) > 500);
  CHECK(check_actor_returns(g, first_still + 3) > 500);
}

TEST_CASE("traffic: braking through a 1.1 s gap beside trucks, the scans register it") {
  // Seed 3, frames 30-39 left out (scripts/jump-table.sh): the constant-velocity guess runs 2 m too far
  // and the trucks fill the scans, so after the search's coarse iterations no start keeps enough points
  // within the fine distance. Ranked by their landing share all the same, one start refines to the
  // truth; dropped, they left nothing to register (nullopt), the tracker lost and the run 0.90 m off.
  const rgbl::SyntheticOptions o = rgbl::scenario_options("traffic", 3);
  const rgbl::SyntheticGenerator g(o);
  const Eigen::Isometry3d truth = g.pose(29).inverse() * g.pose(40);  // T_29_40, camera frames
  const Eigen::Isometry3d velocity = g.pose(28).inverse() * g.pose(29);
  const Eigen::Isometry3d guess = rgbl::se3_exp(11.0 * rgbl::se3_log(velocity));
  REQUIRE((guess.translation() - truth.translation()).norm() > 1.5);
  const auto r = rgbl::register_across_gap(g.render_scan(29), g.render_scan(40), g.calibration().T_cam0_lidar, guess,
                                           g.timestamp(40) - g.timestamp(29), {});
  REQUIRE(r);
  const Eigen::Isometry3d error = truth.inverse() * r->T_reference_query;
  INFO("error " << error.translation().norm() << " m, moved " << r->moved_m << " m " << r->moved_deg << " deg of "
                << r->allowed_m << " m " << r->allowed_deg << " deg, converged " << r->registration.converged
                << ", agreement " << r->registration.agreement << " (runner-up " << r->registration.runner_up_agreement
                << "), probe loss " << r->registration.min_probe_loss);
  CHECK(r->registration.converged);
  CHECK(error.translation().norm() < 0.1);
  // Whether it places the frame is the runner-up rule's call: from this guess another optimum lands
  // almost as many points (0.152 against 0.180) and it would not; from the tracker's own velocity in
  // scripts/jump-table.sh there is no runner-up and it does.
}

TEST_CASE("turn: the heading changes by 90 degrees at junction speed") {
  const rgbl::SyntheticOptions o = rgbl::scenario_options("turn", 1);
  const rgbl::SyntheticGenerator g(o);
  const double turned = heading(g.pose(0)) - heading(g.pose(o.frames - 1));  // left turns decrease psi
  CHECK_THAT(turned / kDeg, WithinAbs(90.0, 1.0));
  // in the bend (radius 12 m) the camera is at 4-5 m/s
  for (int f = 1; f < o.frames; ++f) {
    const double step_heading = std::abs(heading(g.pose(f)) - heading(g.pose(f - 1)));
    if (step_heading < 1e-9) continue;
    const double speed = (g.arc_length(f) - g.arc_length(f - 1)) / o.frame_period;
    INFO("frame " << f);
    CHECK(speed >= 4.0);
    CHECK(speed <= 5.0);
  }
  // buildings along the turn: most of the image is not sky at the bend's middle
  const cv::Mat_<float> depth = g.render_depth(50, 0);
  CHECK(cv::countNonZero(depth > 0.0F) > 0.8 * depth.total());
}

TEST_CASE("foliage: a hedge close on the right, blur that grows with image motion, LiDAR sinking into leaves") {
  rgbl::SyntheticOptions o = rgbl::scenario_options("foliage", 1);
  o.image_noise_sigma = 0.0;  // noise comes after the blur: it would hide what the blur took away
  const rgbl::SyntheticGenerator g(o);
  const int frame = 10;
  const cv::Mat_<float> extent = g.blur_extent(frame, 0);
  const rgbl::PinholeCamera& cam = g.calibration().camera(0).camera;
  // the hedge fills the lower right: ~2.25 m away, strong blur; the street far ahead barely moves
  const Ray right = pixel_ray(g, frame, cam.width - 20, cam.cy + 20);
  const auto hedge = g.intersect(frame, right.origin, right.direction, 100.0);
  REQUIRE(hedge);
  CHECK(g.scene().objects()[hedge->object].kind == rgbl::SurfaceKind::foliage);
  CHECK(hedge->t < 6.0);
  CHECK(extent(static_cast<int>(cam.cy) + 20, cam.width - 20) > 4.0F);
  CHECK(extent(static_cast<int>(cam.cy), static_cast<int>(cam.cx)) < 0.3F);

  // the blur takes detail away where the motion is large, and leaves it where the motion is small
  o.exposure_time = 0.0;
  const rgbl::SyntheticGenerator sharp_gen(o);
  cv::Mat lap_blurred, lap_sharp;
  cv::Laplacian(g.render_image(frame, 0), lap_blurred, CV_32F);
  cv::Laplacian(sharp_gen.render_image(frame, 0), lap_sharp, CV_32F);
  double strong[2] = {0.0, 0.0}, weak[2] = {0.0, 0.0};  // sum of |Laplacian|: blurred, sharp
  for (int v = 1; v + 1 < extent.rows; ++v) {
    for (int u = 1; u + 1 < extent.cols; ++u) {
      double* sums = extent(v, u) > 5.0F ? strong : (extent(v, u) < 0.25F ? weak : nullptr);
      if (sums == nullptr) continue;
      sums[0] += std::abs(lap_blurred.at<float>(v, u));
      sums[1] += std::abs(lap_sharp.at<float>(v, u));
    }
  }
  REQUIRE(strong[1] > 0.0);
  REQUIRE(weak[1] > 0.0);
  CHECK(strong[0] / strong[1] < 0.6);
  CHECK(weak[0] / weak[1] > 0.95);

  // LiDAR: the returns from foliage land deeper than the surface (mean ~0.2 m), the others do not
  double foliage_sum = 0.0, other_sum = 0.0;
  int n_foliage = 0, n_other = 0;
  const Eigen::Isometry3d T = g.pose(frame) * g.calibration().T_cam0_lidar;
  for (const rgbl::LidarPoint& p : g.render_scan(frame)) {
    const Eigen::Vector3d local(p.x, p.y, p.z);
    const auto hit = g.intersect(frame, T.translation(), T.linear() * local.normalized(), 200.0);
    const double error = hit ? local.norm() - hit->t : 1e9;
    if (std::abs(error) > 1.5) continue;  // a beam re-derived from the float point that grazes a silhouette
    const bool leaves = hit->object != rgbl::StreetScene::kGround &&
                        g.scene().objects()[hit->object].kind == rgbl::SurfaceKind::foliage;
    (leaves ? foliage_sum : other_sum) += error;
    ++(leaves ? n_foliage : n_other);
  }
  REQUIRE(n_foliage > 2000);
  CHECK_THAT(foliage_sum / n_foliage, WithinAbs(0.2, 0.03));
  CHECK_THAT(other_sum / n_other, WithinAbs(0.0, 0.005));
}

TEST_CASE("shadows: cast shadows darken the road, the exposure steps and drifts") {
  rgbl::SyntheticOptions o = rgbl::scenario_options("shadows", 1);
  o.image_noise_sigma = 0.0;
  const rgbl::SyntheticGenerator g(o);
  rgbl::SyntheticOptions lit_options = o;
  lit_options.light.cast_shadows = false;
  const rgbl::SyntheticGenerator lit(lit_options);
  const int frame = 5;
  const cv::Mat shaded = g.render_image(frame, 0), open = lit.render_image(frame, 0);
  int road = 0, darker = 0, brighter = 0;
  double ratio_sum = 0.0;
  for (int v = 0; v < shaded.rows; ++v) {
    for (int u = 0; u < shaded.cols; ++u) {
      const Ray r = pixel_ray(g, frame, u, v);
      const auto hit = g.intersect(frame, r.origin, r.direction, 500.0);
      const int a = shaded.at<std::uint8_t>(v, u), b = open.at<std::uint8_t>(v, u);
      brighter += a > b ? 1 : 0;
      if (!hit || hit->object != rgbl::StreetScene::kGround) continue;
      ++road;
      if (a < b - 10) {
        ++darker;
        ratio_sum += static_cast<double>(a) / b;
      }
    }
  }
  INFO("road pixels " << road << ", in shadow " << darker);
  CHECK(darker > road / 10);             // a good part of the road lies in shadow
  CHECK(darker < 0.9 * road);            // and some of it in the sun
  CHECK(ratio_sum / darker < 0.65);      // shadows are clearly darker
  CHECK(brighter == 0);                  // a shadow never lightens anything

  // the exposure: a +30 % step, then a -30 % step, plus a slow drift
  const int step = o.exposure_steps.at(0).frame;
  CHECK_THAT(g.exposure_gain(step) / g.exposure_gain(step - 1), WithinAbs(1.3, 0.03));
  CHECK_THAT(g.exposure_gain(o.exposure_steps.at(1).frame) / g.exposure_gain(o.exposure_steps.at(1).frame - 1),
             WithinAbs(0.7, 0.03));
  const double before = cv::mean(g.render_image(step - 1, 0))[0], after = cv::mean(g.render_image(step, 0))[0];
  CHECK(after > 1.15 * before);
}

TEST_CASE("suburban: the stresses together, the car ahead at the ego speed for the last 40 frames") {
  const rgbl::SyntheticOptions o = rgbl::scenario_options("suburban", 1);
  CHECK(o.scene.hedge_height > 0.0);
  CHECK(o.light.cast_shadows);
  CHECK(o.exposure_time > 0.0);
  REQUIRE(o.actors.size() == 1);
  const rgbl::SyntheticGenerator g(o);
  const rgbl::SpeedProfile car(o.actors[0].speed, o.actors[0].speed_phases);
  const auto gap = [&](int f) { return o.actors[0].s0 + car.distance(g.timestamp(f)) - g.arc_length(f); };
  CHECK(gap(0) > gap(30));
  for (int f = o.frames - 40; f < o.frames; ++f) CHECK_THAT(gap(f), WithinAbs(gap(o.frames - 40), 1e-9));
  const double share = actor_share(g, o.frames - 1);
  CHECK(share > 0.01);
  CHECK(share < 0.10);
}

TEST_CASE("scenarios are deterministic: same seed and options, same bytes, whatever the thread count") {
  for (const char* name : {"traffic", "foliage", "shadows"}) {
    rgbl::SyntheticOptions o = rgbl::scenario_options(name, 4, 20);
    o.width = 240;
    o.height = 72;
    o.cameras = {true, false, true, false};
    const rgbl::SyntheticFrame a = rgbl::SyntheticGenerator(o).render(12);
    o.threads = 1;
    const rgbl::SyntheticFrame b = rgbl::SyntheticGenerator(o).render(12);
    INFO(name);
    CHECK(cv::norm(a.images[0], b.images[0], cv::NORM_INF) == 0.0);
    CHECK(cv::norm(a.images[2], b.images[2], cv::NORM_INF) == 0.0);
    CHECK(a.images[1].empty());
    CHECK(cv::norm(a.depth, b.depth, cv::NORM_INF) == 0.0);
    REQUIRE(a.scan.size() == b.scan.size());
    CHECK(std::memcmp(a.scan.data(), b.scan.data(), a.scan.size() * sizeof(rgbl::LidarPoint)) == 0);
  }
  // another seed, other actors
  const auto a = rgbl::scenario_options("traffic", 1).actors, b = rgbl::scenario_options("traffic", 2).actors;
  CHECK((a.size() != b.size() || a.front().s0 != b.front().s0));
}

TEST_CASE("the KITTI writer writes only the cameras and depth that were rendered") {
  rgbl::SyntheticOptions o = rgbl::scenario_options("plain", 1, 2);
  o.width = 120;
  o.height = 40;
  o.cameras = {true, false, false, false};
  o.render_depth = false;
  const auto dir = std::filesystem::temp_directory_path() / "rgbl_test_scenario_writer";
  std::filesystem::remove_all(dir);
  const rgbl::KittiLayout layout = rgbl::write_kitti(rgbl::SyntheticGenerator(o), dir, 0);
  CHECK(std::filesystem::exists(layout.sequence_dir / "image_0" / "000001.png"));
  CHECK_FALSE(std::filesystem::exists(layout.sequence_dir / "image_1"));
  CHECK_FALSE(std::filesystem::exists(layout.sequence_dir / "image_2"));
  CHECK_FALSE(std::filesystem::exists(layout.sequence_dir / "depth"));
  CHECK(std::filesystem::exists(layout.sequence_dir / "velodyne" / "000001.bin"));
  std::filesystem::remove_all(dir);
}
