#include "rgbl/core/error.hpp"
#include "rgbl/sim/scene.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

using Catch::Matchers::WithinAbs;

namespace {

// A box 2 m wide, deep and high centred 10 m ahead; a pole to the right; the road 1.65 m down.
rgbl::StreetScene toy_scene() {
  rgbl::SceneObject box;
  box.shape = rgbl::SceneObject::Shape::box;
  box.kind = rgbl::SurfaceKind::car;
  box.cx = 0.0;
  box.cz = 10.0;
  box.cy = 1.65 - 1.0;
  box.hx = box.hy = box.hz = 1.0;
  rgbl::SceneObject pole;
  pole.shape = rgbl::SceneObject::Shape::cylinder;
  pole.kind = rgbl::SurfaceKind::pole;
  pole.cx = 5.0;
  pole.cz = 10.0;
  pole.cy = 1.65 - 2.0;
  pole.hx = pole.hz = 0.5;
  pole.hy = 2.0;
  rgbl::GroundDecal stripe;
  stripe.kind = rgbl::SurfaceKind::marking;
  stripe.cx = 0.0;
  stripe.cz = 3.0;
  stripe.half_length = 0.5;
  stripe.half_width = 0.5;
  return rgbl::StreetScene({box, pole}, {stripe}, 1.65);
}

// Every object tried, no grid: the reference for the grid walk.
std::optional<rgbl::RayHit> brute_force(const rgbl::StreetScene& scene, const Eigen::Vector3d& o,
                                        const Eigen::Vector3d& d, double t_max) {
  double best = t_max;
  std::uint8_t face = 0;
  std::uint32_t id = rgbl::StreetScene::kGround;
  for (std::size_t i = 0; i < scene.objects().size(); ++i) {
    if (rgbl::intersect_object(scene.objects()[i], o, d, 1e-6, best, face)) id = static_cast<std::uint32_t>(i);
  }
  if (id != rgbl::StreetScene::kGround) return rgbl::RayHit{best, id, face};
  if (d.y() > 0.0) {
    const double t = (scene.ground_y() - o.y()) / d.y();
    if (t <= t_max) return rgbl::RayHit{t, rgbl::StreetScene::kGround, 0};
  }
  return std::nullopt;
}

}  // namespace

TEST_CASE("rays hit boxes, cylinders and the road where geometry says") {
  const rgbl::StreetScene scene = toy_scene();
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();

  const auto box = scene.intersect(o, Eigen::Vector3d(0.0, 0.0, 2.0), 1e3);  // direction need not be unit
  REQUIRE(box);
  CHECK_THAT(box->t, WithinAbs(4.5, 1e-12));
  CHECK(box->object == 0);
  const rgbl::SurfacePoint front = scene.surface(*box, o, Eigen::Vector3d(0.0, 0.0, 2.0));
  CHECK(front.kind == rgbl::SurfaceKind::car);
  CHECK((front.normal - Eigen::Vector3d(0.0, 0.0, -1.0)).norm() < 1e-12);
  CHECK_THAT(front.v, WithinAbs(1.65, 1e-12));  // height above the road

  const Eigen::Vector3d to_pole(0.5, 0.0, 1.0);
  const auto pole = scene.intersect(o, to_pole, 1e3);
  REQUIRE(pole);
  CHECK(pole->object == 1);
  CHECK_THAT(pole->t, WithinAbs(10.0 - std::sqrt(0.2), 1e-9));

  const auto road = scene.intersect(o, Eigen::Vector3d(0.0, 1.0, 1.0), 1e3);
  REQUIRE(road);
  CHECK(road->object == rgbl::StreetScene::kGround);
  CHECK_THAT(road->t, WithinAbs(1.65, 1e-12));
  CHECK(scene.surface(*road, o, Eigen::Vector3d(0.0, 1.0, 1.0)).kind == rgbl::SurfaceKind::sidewalk);
  const Eigen::Vector3d to_stripe(0.0, 1.65, 3.0);
  const auto stripe = scene.intersect(o, to_stripe, 1e3);
  REQUIRE(stripe);
  CHECK(scene.surface(*stripe, o, to_stripe).kind == rgbl::SurfaceKind::marking);

  CHECK_FALSE(scene.intersect(o, Eigen::Vector3d(0.0, -1.0, 0.1), 1e3));  // sky
  CHECK_FALSE(scene.intersect(o, Eigen::Vector3d(0.0, 0.0, 1.0), 8.0));   // t_max before the box

  // the hits lie on the surfaces, by the independent distance function
  CHECK(std::abs(scene.signed_distance(o + box->t * Eigen::Vector3d(0.0, 0.0, 2.0))) < 1e-12);
  CHECK(std::abs(scene.signed_distance(o + pole->t * to_pole)) < 1e-9);
  CHECK(std::abs(scene.signed_distance(Eigen::Vector3d(0.0, 1.65, 1.65))) < 1e-12);
  CHECK_THAT(scene.signed_distance(Eigen::Vector3d(0.0, 0.0, 8.0)), WithinAbs(1.0, 1e-12));  // box 1 m ahead
}

TEST_CASE("the grid walk finds exactly what trying every object finds") {
  rgbl::SyntheticOptions options;
  options.frames = 30;
  options.path.kind = rgbl::PathKind::curve;
  const rgbl::SyntheticGenerator generator(options);
  const rgbl::StreetScene& scene = generator.scene();
  REQUIRE(scene.objects().size() > 50);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int hits = 0, objects = 0;
  for (int i = 0; i < 20000; ++i) {
    const double s = 15.0 * (unit(rng) + 1.0);
    const Eigen::Vector2d p = generator.path().point(s, 2.0 * unit(rng));
    const Eigen::Vector3d o(p.x(), 1.2 * unit(rng), p.y());
    const Eigen::Vector3d d(unit(rng), 0.5 * unit(rng), unit(rng));
    const double t_max = 150.0;
    const auto a = scene.intersect(o, d, t_max);
    const auto b = brute_force(scene, o, d, t_max);
    REQUIRE(a.has_value() == b.has_value());
    if (!a) continue;
    ++hits;
    objects += a->object != rgbl::StreetScene::kGround ? 1 : 0;
    REQUIRE(a->object == b->object);
    REQUIRE(a->face == b->face);
    REQUIRE(a->t == b->t);
  }
  CHECK(hits > 15000);
  CHECK(objects > 5000);
}

TEST_CASE("the street: facades on both sides, parked cars, poles, and a clear driving lane") {
  rgbl::SyntheticOptions options;
  for (const auto kind : {rgbl::PathKind::straight, rgbl::PathKind::curve, rgbl::PathKind::loop}) {
    options.path.kind = kind;
    options.frames = kind == rgbl::PathKind::loop ? 300 : 100;  // a 100 m loop is a roundabout: nothing inside
    const rgbl::SyntheticGenerator generator(options);
    const rgbl::StreetScene& scene = generator.scene();
    int facades_left = 0, facades_right = 0, cars = 0, poles = 0;
    for (const auto& o : scene.objects()) {
      // which side of the track at the nearest frame?
      int nearest = 0;
      double best = 1e18;
      for (int i = 0; i < options.frames; ++i) {
        const double d = (generator.pose(i).translation() - Eigen::Vector3d(o.cx, 0.0, o.cz)).norm();
        if (d < best) {
          best = d;
          nearest = i;
        }
      }
      const Eigen::Vector3d local = generator.pose(nearest).inverse() * Eigen::Vector3d(o.cx, 0.0, o.cz);
      if (o.kind == rgbl::SurfaceKind::facade && best < 30.0) (local.x() > 0.0 ? facades_right : facades_left)++;
      cars += o.kind == rgbl::SurfaceKind::car ? 1 : 0;
      poles += o.kind == rgbl::SurfaceKind::pole ? 1 : 0;
    }
    INFO("path " << rgbl::to_string(kind));
    CHECK(facades_left >= 4);
    CHECK(facades_right >= 4);
    CHECK(cars >= 10);
    CHECK(poles >= 6);
    // The car's own lane is free: 1 m either side of the track, up to 3 m above the road.
    for (double s = 0.0; s <= generator.path().length(); s += 0.5) {
      for (const double lateral : {-1.0, 0.0, 1.0}) {
        const Eigen::Vector2d p = generator.path().point(s, lateral);
        for (const double y : {1.6, 0.0, -1.3}) {
          REQUIRE(scene.signed_distance(Eigen::Vector3d(p.x(), y, p.y())) > 0.04);
        }
      }
    }
    // and it is road
    const Eigen::Vector3d down(0.0, 1.0, 0.0);
    const auto hit = scene.intersect(generator.pose(10).translation(), down, 10.0);
    REQUIRE(hit);
    const auto kind_below = scene.surface(*hit, generator.pose(10).translation(), down).kind;
    CHECK((kind_below == rgbl::SurfaceKind::road || kind_below == rgbl::SurfaceKind::marking));
  }
}

TEST_CASE("a street of identical blocks: every ray meets the same surface one block on, only on a straight path") {
  rgbl::SyntheticOptions options;
  options.path.kind = rgbl::PathKind::straight;
  options.frames = 250;
  options.scene.repeat_length = 100.0;
  const rgbl::SyntheticGenerator generator(options);
  const rgbl::StreetScene& scene = generator.scene();
  int facades = 0, cars = 0;
  for (const auto& o : scene.objects()) {
    facades += o.kind == rgbl::SurfaceKind::facade ? 1 : 0;
    cars += o.kind == rgbl::SurfaceKind::car ? 1 : 0;
  }
  CHECK(facades >= 8);
  CHECK(cars >= 10);
  // Rays from frame 20 and from 100 m further on (frame 120 at 10 m/s) in the same directions: the
  // same object kind, seed, face and surface coordinates, at the same distance; the ground differs
  // only in the asphalt's texture, which is not the scene's business here.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-1.2, 1.2), pitch(-0.3, 0.25);
  const Eigen::Vector3d a = generator.pose(20).translation(), b = generator.pose(120).translation();
  REQUIRE_THAT((b - a).norm(), WithinAbs(100.0, 1e-9));
  int objects_hit = 0;
  for (int i = 0; i < 2000; ++i) {
    const double yaw = angle(rng), tilt = pitch(rng);
    const Eigen::Vector3d d(std::sin(yaw) * std::cos(tilt), tilt, std::cos(yaw) * std::cos(tilt));
    const auto ha = scene.intersect(a, d, 80.0), hb = scene.intersect(b, d, 80.0);
    REQUIRE(ha.has_value() == hb.has_value());
    if (!ha) continue;
    CHECK_THAT(hb->t, WithinAbs(ha->t, 1e-6));
    if (ha->object == rgbl::StreetScene::kGround) {
      CHECK(hb->object == rgbl::StreetScene::kGround);
      continue;
    }
    ++objects_hit;
    const rgbl::SurfacePoint sa = scene.surface(*ha, a, d), sb = scene.surface(*hb, b, d);
    CHECK(sa.kind == sb.kind);
    CHECK(sa.seed == sb.seed);
    CHECK(sa.face == sb.face);
    CHECK_THAT(sb.u, WithinAbs(sa.u, 1e-6));
    CHECK_THAT(sb.v, WithinAbs(sa.v, 1e-6));
  }
  CHECK(objects_hit > 800);

  options.path.kind = rgbl::PathKind::curve;
  try {
    const rgbl::SyntheticGenerator curved(options);
    FAIL("identical blocks were laid along a curve");
  } catch (const rgbl::ConfigError& e) {
    CHECK(e.key() == "scene.repeat_length");
  }
  options.scene.repeat_length = 10.0;
  CHECK_THROWS_AS(options.scene.validate(), rgbl::ConfigError);
}
