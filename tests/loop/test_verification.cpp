#include "rgbl/loop/verification.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/io/sequence.hpp"
#include "mapped_drive.hpp"
#include "support/data.hpp"

#include <catch2/catch.hpp>



TEST_CASE("loop verification measures the relative pose of two keyframes of one real drive") {
  const auto dir = rgbl::test::kitti_seq04();
  if (!dir) return;
  const rgbl::test::Mapped m = rgbl::test::map_drive(rgbl::open_kitti_odometry(*dir), 30);
  const rgbl::Map& map = m.system->map();
  const auto ids = map.keyframe_ids();
  REQUIRE(ids.size() >= 6);
  const rgbl::Keyframe& current = *map.keyframe(ids.back());
  int verified = 0;
  double worst_m = 0.0, worst_deg = 0.0;
  for (std::size_t k = 0; k + 1 < ids.size(); ++k) {
    const rgbl::Keyframe& earlier = *map.keyframe(ids[k]);
    const double apart = (current.center() - earlier.center()).norm();
    const auto v = rgbl::verify_loop(m.calibration.camera, current, map, ids[k]);
    CAPTURE(k, apart, v.has_value());
    if (!v) continue;
    ++verified;
    // the measured relative pose agrees with the tracked one (itself within cm of the truth here)
    const Eigen::Isometry3d tracked = current.T_cam_world * earlier.T_cam_world.inverse();
    const Eigen::Isometry3d error = tracked.inverse() * v->constraint.T_current_matched;
    CAPTURE(v->counts.matches, v->counts.ransac_inliers, v->counts.inliers, error.translation().norm());
    worst_m = std::max(worst_m, error.translation().norm());
    worst_deg = std::max(worst_deg, rgbl::rotation_angle(error.linear()) * 180.0 / M_PI);
    CHECK(v->counts.inliers >= 40);
    CHECK(v->constraint.matched == ids[k]);
    CHECK(v->constraint.current == current.id);
  }
  CHECK(verified >= 3);  // keyframes up to ~20 m behind share landmarks ahead
  WARN("worst " << worst_m << " m " << worst_deg << " deg over " << verified);
  CHECK(worst_m < 0.06);  // measured 0.029 m, 0.03 deg
  CHECK(worst_deg < 0.1);
}

TEST_CASE("loop verification rejects every keyframe of another drive") {
  const auto seq04 = rgbl::test::kitti_seq04();
  const auto raw = rgbl::test::find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync");
  if (!seq04 || !raw) return;
  const rgbl::test::Mapped rural = rgbl::test::map_drive(rgbl::open_kitti_odometry(*seq04), 30);
  const rgbl::test::Mapped city = rgbl::test::map_drive(rgbl::open_kitti_raw(*raw), 10);
  const rgbl::Map& rural_map = rural.system->map();
  const rgbl::Map& city_map = city.system->map();
  // The margin of the geometry alone: with every keypoint matched to its nearest landmark (no distance
  // bound, no ratio test) and every count threshold at 3, how many matches does the best false pair
  // get to agree?
  rgbl::LoopVerificationOptions relaxed;
  relaxed.max_hamming = 256;
  relaxed.ratio = 1.0F;
  relaxed.min_ransac_inliers = 3;
  relaxed.min_inliers = 3;
  relaxed.min_inlier_ratio = 0.0;
  int tried = 0, most_matches = 0, most_inliers = 0;
  for (const rgbl::KeyframeId c : city_map.keyframe_ids()) {
    for (const rgbl::KeyframeId r : rural_map.keyframe_ids()) {
      ++tried;
      CHECK_FALSE(rgbl::verify_loop(city.calibration.camera, *city_map.keyframe(c), rural_map, r).has_value());
      CHECK_FALSE(rgbl::verify_loop(rural.calibration.camera, *rural_map.keyframe(r), city_map, c).has_value());
      rgbl::LoopVerificationCounts a, b;
      (void)rgbl::verify_loop(city.calibration.camera, *city_map.keyframe(c), rural_map, r, relaxed, &a);
      (void)rgbl::verify_loop(rural.calibration.camera, *rural_map.keyframe(r), city_map, c, relaxed, &b);
      most_matches = std::max({most_matches, a.matches, b.matches});
      most_inliers = std::max({most_inliers, a.ransac_inliers, b.ransac_inliers, a.inliers, b.inliers});
    }
  }
  CHECK(tried >= 20);
  // measured: up to 478 matches, at most 5 agreeing (the true pairs of the test above: 56 to 383)
  CAPTURE(most_matches, most_inliers);
  CHECK(most_matches > 100);
  CHECK(most_inliers < rgbl::LoopVerificationOptions{}.min_inliers / 2);
}

TEST_CASE("loop verification options are checked, naming the field") {
  rgbl::LoopVerificationOptions o;
  o.ratio = 0.0F;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("loop_verification.ratio"));
  o = {};
  o.min_inliers = 2;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("loop_verification.min_inliers"));
  // a keyframe whose arrays disagree is refused before anything is indexed
  rgbl::Map map;
  rgbl::Keyframe k;
  k.keypoints.resize(3);
  k.descriptors.resize(2);
  k.depth.resize(3);
  const rgbl::KeyframeId id = map.add_keyframe(rgbl::Keyframe{});
  const rgbl::PinholeCamera camera{};
  CHECK_THROWS_WITH(rgbl::verify_loop(camera, k, map, id), Catch::Contains("current keyframe") && Catch::Contains("2 descriptors"));
}
