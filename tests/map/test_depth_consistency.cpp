#include "rgbl/map/depth_consistency.hpp"

#include "support/kitti_camera.hpp"

#include <catch2/catch.hpp>

#include <cmath>

namespace {

// A landmark at `point` seen from camera centres `centers` (looking along world z) at its exact pixel,
// level 0, with its camera z plus `depth_error` as depth (sigma 0.03 m); no depth where `with_depth`
// is false.
double scale_of(const std::vector<Eigen::Vector3d>& centers, const Eigen::Vector3d& point,
                const std::vector<double>& depth_error, const std::vector<bool>& with_depth) {
  const rgbl::PinholeCamera camera = rgbl::test::kitti_camera();
  rgbl::Map map;
  const auto l = map.add_landmark(point, rgbl::KeyframeId{0});
  for (std::size_t k = 0; k < centers.size(); ++k) {
    rgbl::Keyframe kf;
    kf.T_cam_world = Eigen::Isometry3d::Identity();
    kf.T_cam_world.translation() = -centers[k];
    const Eigen::Vector3d p_cam = kf.T_cam_world * point;
    const Eigen::Vector2d px = camera.project_unchecked(p_cam);
    rgbl::Keypoint kp;
    kp.x = static_cast<float>(px.x());
    kp.y = static_cast<float>(px.y());
    kf.keypoints = {kp};
    kf.descriptors = {rgbl::Descriptor{}};
    kf.depth = {with_depth[k] ? static_cast<float>(p_cam.z() + depth_error[k]) : 0.0F};
    kf.depth_sigma = {with_depth[k] ? 0.03F : 0.0F};
    map.add_observation(l, map.add_keyframe(std::move(kf)), 0);
  }
  return rgbl::depth_consistency_scale(map, *map.landmark(l), camera);
}

}  // namespace

TEST_CASE("depth consistency: depths that disagree with the landmark's parallax are weighed less") {
  // driving 3 m past a hedge point 2 m to the side and 6 m ahead: the rays pin it within centimetres
  const std::vector<Eigen::Vector3d> drive = {{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 2.0}, {0.0, 0.0, 3.0}};
  const Eigen::Vector3d hedge(2.0, 0.5, 6.0);
  const std::vector<bool> all(4, true);
  CHECK(scale_of(drive, hedge, {0.0, 0.0, 0.0, 0.0}, all) == 1.0);
  // within their sigma, both ways
  CHECK(scale_of(drive, hedge, {0.02, -0.03, 0.01, 0.02}, all) == 1.0);
  // every scan 0.15 m deep (5 sigmas; the same each time, which the scatter about their mean never shows)
  const double deep = scale_of(drive, hedge, {0.15, 0.15, 0.15, 0.15}, all);
  // sqrt((0.15^2 - v) / 0.03^2): 4.91, v the triangulation's own variance along z ((0.029 m)^2)
  CHECK(deep > 4.8);
  CHECK(deep <= 5.0);  // 0.15 / 0.03: all of it the depths'
  // two keyframes with depth of four still tell (the rays come from all four)
  CHECK(scale_of(drive, hedge, {0.15, 0.0, 0.15, 0.0}, {true, false, true, false}) > 2.0);
  // one with depth says nothing, nor do two keyframes
  CHECK(scale_of(drive, hedge, {0.15, 0.15, 0.15, 0.15}, {true, false, false, false}) == 1.0);
  CHECK(scale_of({drive[0], drive[3]}, hedge, {0.15, 0.15}, {true, true}) == 1.0);
  // straight at a point ahead the rays coincide: no parallax to judge the depths by
  CHECK(scale_of(drive, Eigen::Vector3d(0.0, 0.0, 30.0), {0.5, 0.5, 0.5, 0.5}, all) == 1.0);
  // a distant point seen over a short baseline: its triangulation's own variance along z absorbs 0.15 m
  CHECK(scale_of(drive, Eigen::Vector3d(3.0, 0.5, 60.0), {0.15, 0.15, 0.15, 0.15}, all) == 1.0);
}

TEST_CASE("depth consistency: chi2 at 95 %") {
  CHECK(rgbl::chi2_95(2.0) == Approx(5.991).epsilon(0.01));
  CHECK(rgbl::chi2_95(3.0) == Approx(7.815).epsilon(0.01));
  CHECK(rgbl::chi2_95(10.0) == Approx(18.307).epsilon(0.01));
}
