#include "rgbl/sim/actors.hpp"

#include "hash.hpp"
#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>

namespace rgbl {

void Actor::validate(const char* key) const {
  require(!parts.empty(), key, "an actor with at least one part");
  for (const ActorPart& p : parts) {
    require(std::isfinite(p.back) && std::isfinite(p.front) && p.back < p.front, key, "parts with back < front");
    require(p.half_width > 0.0 && p.half_width < 5.0, key, "parts with a half width in (0, 5) m");
    require(p.bottom >= 0.0 && p.bottom < p.top && p.top < 10.0, key, "parts with 0 <= bottom < top < 10 m");
  }
  require(std::isfinite(lateral) && std::isfinite(s0), key, "a finite lateral offset and start");
  SpeedProfile(speed, speed_phases, key);  // throws when the speed would become negative
}

double Actor::length() const {
  double lo = 0.0, hi = 0.0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    lo = i == 0 ? parts[i].back : std::min(lo, parts[i].back);
    hi = i == 0 ? parts[i].front : std::max(hi, parts[i].front);
  }
  return hi - lo;
}

Actor make_vehicle(VehicleKind kind, std::uint32_t seed) {
  sim_detail::Rng rng(seed);
  Actor a;
  a.seed = seed;
  switch (kind) {
    case VehicleKind::car: {
      const double len = rng.uniform(4.1, 4.8), hw = 0.5 * rng.uniform(1.72, 1.86);
      const double body = rng.uniform(0.78, 0.92), cabin = body + rng.uniform(0.45, 0.56);
      const double cabin_len = len * rng.uniform(0.48, 0.58);
      a.parts.push_back({SurfaceKind::car, -0.5 * len, 0.5 * len, hw, 0.0, body});
      const double c = -0.08 * len;
      a.parts.push_back({SurfaceKind::cabin, c - 0.5 * cabin_len, c + 0.5 * cabin_len, hw - 0.1, body, cabin});
      break;
    }
    case VehicleKind::van: {
      // a delivery van: a short bonnet, then a tall box with rear windows
      const double len = rng.uniform(5.0, 5.6), hw = 0.5 * rng.uniform(1.95, 2.05);
      const double body = rng.uniform(0.95, 1.05), roof = rng.uniform(2.3, 2.5);
      a.parts.push_back({SurfaceKind::car, -0.5 * len, 0.5 * len, hw, 0.0, body});
      a.parts.push_back({SurfaceKind::cabin, -0.5 * len, 0.5 * len - 0.85, hw - 0.03, body, roof});
      break;
    }
    case VehicleKind::truck: {
      // a cab in front of a cargo box (the container's look: ribs, labels, rust)
      const double cab_len = rng.uniform(2.0, 2.4), cargo_len = rng.uniform(6.0, 8.5), hw = 0.5 * rng.uniform(2.4, 2.5);
      const double cab_top = rng.uniform(2.8, 3.1), cargo_top = rng.uniform(3.4, 3.9);
      const double len = cab_len + 0.3 + cargo_len, back = -0.5 * len;
      const double front = back + len;
      a.parts.push_back({SurfaceKind::car, front - cab_len, front, hw, 0.0, 1.35});
      a.parts.push_back({SurfaceKind::cabin, front - cab_len, front - 0.25, hw - 0.05, 1.35, cab_top});
      a.parts.push_back({SurfaceKind::container, back, back + cargo_len, hw, 0.9, cargo_top});
      a.parts.push_back({SurfaceKind::car, back + 0.4, back + cargo_len - 0.4, hw - 0.15, 0.0, 0.9});  // chassis, wheels
      break;
    }
  }
  return a;
}

std::vector<SceneObject> actor_boxes(const std::vector<Actor>& actors, const DrivePath& path, double ground_y,
                                     double t) {
  std::vector<SceneObject> boxes;
  for (const Actor& a : actors) {
    const double driven = SpeedProfile(a.speed, a.speed_phases).distance(t);
    const double s = a.s0 + (a.oncoming ? -driven : driven);
    const PathPoint p = path.at(s);
    const Eigen::Vector2d centre = Eigen::Vector2d(p.x, p.z) + a.lateral * p.right();
    const Eigen::Vector2d forward = a.oncoming ? Eigen::Vector2d(-p.forward()) : p.forward();
    for (const ActorPart& part : a.parts) {
      SceneObject o;
      o.shape = SceneObject::Shape::box;
      o.kind = part.kind;
      o.seed = a.seed;
      const Eigen::Vector2d c = centre + 0.5 * (part.back + part.front) * forward;
      o.cx = c.x();
      o.cz = c.y();
      o.cy = ground_y - 0.5 * (part.bottom + part.top);
      o.ax = forward.x();
      o.az = forward.y();
      o.hx = 0.5 * (part.front - part.back);
      o.hy = 0.5 * (part.top - part.bottom);
      o.hz = part.half_width;
      boxes.push_back(o);
    }
  }
  return boxes;
}

}  // namespace rgbl
