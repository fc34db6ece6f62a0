// Objects whose residuals err together (rgbl/tracking/object_residuals.hpp): static objects with
// independent noise and a car whose landmarks lie where it was a few frames ago, at an exactly known pose.
#include "rgbl/tracking/object_residuals.hpp"
#include "rgbl/tracking/options.hpp"

#include "rgbl/core/error.hpp"
#include "support/kitti_camera.hpp"

#include <catch2/catch.hpp>

#include <random>

namespace {

rgbl::PinholeCamera object_camera() { return rgbl::test::kitti_camera(); }

// grouped as the tracker groups them
rgbl::ObjectGrouping tracker_grouping() {
  const rgbl::TrackerOptions t;
  return {t.moving_label_radius, t.ransac_min_tolerance, t.ransac_relative_tolerance};
}

struct ObjectScene {
  std::vector<rgbl::PoseObservation> observations;
  std::vector<int> object;  // per observation: which object made it (-1 none)
};

// count points on a patch around pixel (u, v) at depth z (a fronto-parallel surface), measured with
// the given pixel and depth noise; the landmark is the true point moved by `moved` (camera frame).
void add_object(ObjectScene& scene, std::mt19937& rng, int id, double u, double v, double z, int count,
                const Eigen::Vector3d& moved = Eigen::Vector3d::Zero()) {
  const rgbl::PinholeCamera c = object_camera();
  std::uniform_real_distribution<double> offset(-15.0, 15.0);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < count; ++k) {
    rgbl::PoseObservation o;
    const Eigen::Vector2d px(u + offset(rng), v + offset(rng));
    const Eigen::Vector3d p = c.unproject(px, z);
    o.sigma_px = 1.0;
    o.depth_sigma = 0.01 * z;
    o.p_world = p + moved;
    o.pixel = px + o.sigma_px * Eigen::Vector2d(unit(rng), unit(rng));
    o.depth = z + o.depth_sigma * unit(rng);
    scene.observations.push_back(o);
    scene.object.push_back(id);
  }
}

}  // namespace

TEST_CASE("object residuals: a car that moved with the camera is flagged, static objects are not",
          "[tracking][objects]") {
  const rgbl::ObjectResidualOptions options;
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  // the true pose
  int false_flags = 0, car_found = 0;
  for (unsigned seed = 1; seed <= 50; ++seed) {
    std::mt19937 rng(seed);
    ObjectScene scene;
    add_object(scene, rng, 0, 100.0, 150.0, 12.0, 25);
    add_object(scene, rng, 1, 250.0, 120.0, 25.0, 25);
    add_object(scene, rng, 2, 550.0, 130.0, 18.0, 25);
    add_object(scene, rng, 3, 700.0, 160.0, 9.0, 25);
    // a car 30 m ahead: its landmarks were made where it was, 0.6 m nearer (it drove on with the
    // camera); one sigma of its depth is 0.3 m, so every point passes the per-point tests
    add_object(scene, rng, 4, 400.0, 140.0, 30.0, 20, Eigen::Vector3d(0.0, 0.0, -0.6));
    const std::vector<bool> inlier(scene.observations.size(), true);
    const auto result =
        rgbl::objects_against_pose(object_camera(), T, scene.observations, inlier, {}, tracker_grouping(), options, false);
    CHECK(result.objects == 5);
    bool car = true;
    for (std::size_t j = 0; j < scene.observations.size(); ++j) {
      if (scene.object[j] == 4) car = car && result.flagged[j];
      else if (result.flagged[j]) ++false_flags;
    }
    if (car) ++car_found;
  }
  CHECK(false_flags == 0);
  CHECK(car_found == 50);
}

TEST_CASE("object residuals: the pose stands on the rest, and excluded and outlier points are not grouped",
          "[tracking][objects]") {
  const rgbl::ObjectResidualOptions options;
  std::mt19937 rng(7);
  ObjectScene scene;
  add_object(scene, rng, 0, 100.0, 150.0, 12.0, 10);
  add_object(scene, rng, 1, 250.0, 120.0, 25.0, 10);
  add_object(scene, rng, 2, 550.0, 130.0, 18.0, 10);
  add_object(scene, rng, 4, 400.0, 140.0, 30.0, 20, Eigen::Vector3d(0.0, 0.0, -0.6));  // 40 % of the points
  const std::vector<bool> inlier(scene.observations.size(), true);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  auto result =
      rgbl::objects_against_pose(object_camera(), T, scene.observations, inlier, {}, tracker_grouping(), options, false);
  CHECK(result.objects == 4);
  CHECK(result.flagged_objects == 0);  // over max_share: not a minority to leave out

  // the same car at 20 % of the points is flagged; excluded (road) and outlier points take no part
  std::vector<bool> exclude(scene.observations.size(), false), some_inliers = inlier;
  for (std::size_t j = 0; j < 10; ++j) exclude[j] = true;  // object 0 is the road
  for (std::size_t j = 30; j < 35; ++j) some_inliers[j] = false;
  rgbl::ObjectResidualOptions larger = options;
  larger.max_share = 0.5;
  result = rgbl::objects_against_pose(object_camera(), T, scene.observations, some_inliers, exclude, tracker_grouping(),
                                      larger, false);
  CHECK(result.objects == 3);
  CHECK(result.flagged_objects == 1);
  for (std::size_t j = 0; j < scene.observations.size(); ++j)
    CHECK(result.flagged[j] == (j >= 35));

  // fewer objects than min_objects: nothing to measure the overdispersion by
  rgbl::ObjectResidualOptions strict = larger;
  strict.min_objects = 4;
  CHECK(rgbl::objects_against_pose(object_camera(), T, scene.observations, some_inliers, exclude, tracker_grouping(),
                                   strict, false)
            .flagged_objects == 0);

  rgbl::ObjectResidualOptions bad;
  bad.max_share = 1.0;
  CHECK_THROWS_AS(bad.validate(), rgbl::ConfigError);
  bad = {};
  bad.min_points = 1;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("tracker.object_test.min_points"));
}
