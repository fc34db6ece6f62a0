#include "rgbl/sim/scene.hpp"

#include "hash.hpp"
#include "rgbl/core/error.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace rgbl {
namespace {

using sim_detail::Rng;

using sim_detail::kInf;

// Footprint of an object in the ground plane: an oriented rectangle (cylinders: their square).
struct Footprint {
  double cx, cz, ax, az, hx, hz;
};

Footprint footprint(const SceneObject& o) { return {o.cx, o.cz, o.ax, o.az, o.hx, o.hz}; }

Footprint footprint(const GroundDecal& d) { return {d.cx, d.cz, d.ax, d.az, d.half_length, d.half_width}; }

// Distance from a point to a footprint rectangle (0 inside).
double distance_to(const Footprint& f, double x, double z) {
  const double rx = x - f.cx, rz = z - f.cz;
  const double lx = std::abs(rx * f.ax + rz * f.az) - f.hx;
  const double lz = std::abs(-rx * f.az + rz * f.ax) - f.hz;
  return std::hypot(std::max(lx, 0.0), std::max(lz, 0.0));
}

// Axis-aligned bounds of a footprint.
void bounds(const Footprint& f, double& xmin, double& xmax, double& zmin, double& zmax) {
  const double ex = std::abs(f.ax) * f.hx + std::abs(f.az) * f.hz;
  const double ez = std::abs(f.az) * f.hx + std::abs(f.ax) * f.hz;
  xmin = f.cx - ex;
  xmax = f.cx + ex;
  zmin = f.cz - ez;
  zmax = f.cz + ez;
}

// Separating-axis test of a footprint against the square cell [x, x+size] x [z, z+size]; the
// bounding boxes are known to overlap, so only the rectangle's own axes remain to be tried.
bool overlaps_cell(const Footprint& f, double x, double z, double size) {
  constexpr double kEps = 1e-6;
  const double corners[4][2] = {{x, z}, {x + size, z}, {x, z + size}, {x + size, z + size}};
  const double axes[2][2] = {{f.ax, f.az}, {-f.az, f.ax}};
  const double half[2] = {f.hx, f.hz};
  for (int a = 0; a < 2; ++a) {
    const double c = f.cx * axes[a][0] + f.cz * axes[a][1];
    double lo = kInf, hi = -kInf;
    for (const auto& p : corners) {
      const double proj = p[0] * axes[a][0] + p[1] * axes[a][1];
      lo = std::min(lo, proj);
      hi = std::max(hi, proj);
    }
    if (hi < c - half[a] - kEps || lo > c + half[a] + kEps) return false;
  }
  return true;
}

// Centreline samples of the road, for keeping objects off it.
class RoadClearance {
 public:
  RoadClearance(const DrivePath& path, double centre_lateral, double s_begin, double s_end) {
    const double step = 0.5;
    for (double s = s_begin; s <= s_end; s += step) points_.push_back(path.point(s, centre_lateral));
  }

  // Smallest distance between the footprint and the road's centreline.
  double distance(const Footprint& f) const {
    const double reach = std::hypot(f.hx, f.hz);
    double best = kInf;
    for (const auto& p : points_) {
      const double dx = p.x() - f.cx, dz = p.y() - f.cz;
      if (std::abs(dx) > best + reach || std::abs(dz) > best + reach) continue;
      best = std::min(best, distance_to(f, p.x(), p.y()));
    }
    return best;
  }

 private:
  std::vector<Eigen::Vector2d> points_;
};

// Chops [s0, s1] into pieces of at most `step` metres and hands each piece's chord at `lateral` to fn.
template <typename Fn>
void for_each_chord(const DrivePath& path, double s0, double s1, double step, double lateral, Fn&& fn) {
  const int n = std::max(1, static_cast<int>(std::ceil((s1 - s0) / step)));
  const double ds = (s1 - s0) / n;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d a = path.point(s0 + i * ds, lateral);
    const Eigen::Vector2d b = path.point(s0 + (i + 1) * ds, lateral);
    fn(a, b);
  }
}

GroundDecal chord_decal(SurfaceKind kind, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width,
                        double overlap) {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  GroundDecal g;
  g.kind = kind;
  g.cx = 0.5 * (a.x() + b.x());
  g.cz = 0.5 * (a.y() + b.y());
  g.ax = len > 0.0 ? d.x() / len : 1.0;
  g.az = len > 0.0 ? d.y() / len : 0.0;
  g.half_length = 0.5 * len + overlap;
  g.half_width = half_width;
  return g;
}

SceneObject upright_box(SurfaceKind kind, std::uint32_t seed, const Eigen::Vector2d& centre, const Eigen::Vector2d& axis,
                        double half_length, double half_width, double ground_y, double bottom, double top) {
  SceneObject o;
  o.shape = SceneObject::Shape::box;
  o.kind = kind;
  o.seed = seed;
  o.cx = centre.x();
  o.cz = centre.y();
  o.cy = ground_y - 0.5 * (bottom + top);
  o.ax = axis.x();
  o.az = axis.y();
  o.hx = half_length;
  o.hy = 0.5 * (top - bottom);
  o.hz = half_width;
  return o;
}

SceneObject cylinder(SurfaceKind kind, std::uint32_t seed, const Eigen::Vector2d& centre, double radius, double ground_y,
                     double height) {
  SceneObject o;
  o.shape = SceneObject::Shape::cylinder;
  o.kind = kind;
  o.seed = seed;
  o.cx = centre.x();
  o.cz = centre.y();
  o.cy = ground_y - 0.5 * height;
  o.hx = o.hz = radius;
  o.hy = 0.5 * height;
  return o;
}

double box_sdf(const SceneObject& o, const Eigen::Vector3d& p) {
  const double rx = p.x() - o.cx, rz = p.z() - o.cz;
  const double qx = std::abs(rx * o.ax + rz * o.az) - o.hx;
  const double qy = std::abs(p.y() - o.cy) - o.hy;
  const double qz = std::abs(-rx * o.az + rz * o.ax) - o.hz;
  const double outside = std::sqrt(std::pow(std::max(qx, 0.0), 2) + std::pow(std::max(qy, 0.0), 2) +
                                   std::pow(std::max(qz, 0.0), 2));
  return outside + std::min(std::max({qx, qy, qz}), 0.0);
}

double cylinder_sdf(const SceneObject& o, const Eigen::Vector3d& p) {
  const double dr = std::hypot(p.x() - o.cx, p.z() - o.cz) - o.hx;
  const double dy = std::abs(p.y() - o.cy) - o.hy;
  return std::min(std::max(dr, dy), 0.0) + std::hypot(std::max(dr, 0.0), std::max(dy, 0.0));
}

}  // namespace

void StreetOptions::validate() const {
  require(camera_height > 0.2 && camera_height < 10.0, "scene.camera_height", "a height in (0.2, 10) m");
  require(road_half_width >= 3.0, "scene.road_half_width", "at least 3 m");
  require(parking_width >= 0.0 && parking_width < road_half_width - 2.0, "scene.parking_width",
          "a width >= 0 that leaves a driving lane of at least 2 m");
  require(std::abs(lane_offset) <= road_half_width - parking_width - 1.0, "scene.lane_offset",
          "an offset that keeps the camera 1 m inside the driving lanes");
  require(sidewalk_width >= 1.0, "scene.sidewalk_width", "at least 1 m");
  require(building_min_length >= 4.0 && building_max_length >= building_min_length, "scene.building_min_length",
          "4 m <= building_min_length <= building_max_length");
  require(building_min_height >= 3.0 && building_max_height >= building_min_height, "scene.building_min_height",
          "3 m <= building_min_height <= building_max_height");
  require(building_max_gap >= 0.0, "scene.building_max_gap", "a gap >= 0 m");
  require(parked_probability >= 0.0 && parked_probability <= 1.0, "scene.parked_probability", "a probability in [0, 1]");
  require(container_probability >= 0.0 && container_probability <= 1.0, "scene.container_probability",
          "a probability in [0, 1]");
  require(pole_spacing >= 2.0, "scene.pole_spacing", "at least 2 m");
  require(tree_spacing >= 2.0, "scene.tree_spacing", "at least 2 m");
  require(tree_offset >= 0.3 && tree_offset <= sidewalk_width, "scene.tree_offset", "0.3 m up to the sidewalk's width");
  require(hedge_height >= 0.0 && hedge_height <= 10.0, "scene.hedge_height", "a height in [0, 10] m (0 = no hedge)");
  require(hedge_offset >= 0.0 && hedge_depth >= 0.1 && hedge_offset + hedge_depth <= sidewalk_width,
          "scene.hedge_offset", "hedge_offset >= 0, hedge_depth >= 0.1 m, both within the sidewalk");
  require(repeat_length == 0.0 || repeat_length >= 20.0, "scene.repeat_length",
          "0 (no repetition) or a block of at least 20 m");
}

bool intersect_object(const SceneObject& ob, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      double t_min, double& t_best, std::uint8_t& face) {
  const double ox = origin.x(), oy = origin.y(), oz = origin.z();
  const double dx = direction.x(), dy = direction.y(), dz = direction.z();
  const double rx = ox - ob.cx, ry = oy - ob.cy, rz = oz - ob.cz;
  if (ob.shape == SceneObject::Shape::box) {
    const double l[3] = {rx * ob.ax + rz * ob.az, ry, -rx * ob.az + rz * ob.ax};
    const double dl[3] = {dx * ob.ax + dz * ob.az, dy, -dx * ob.az + dz * ob.ax};
    const double h[3] = {ob.hx, ob.hy, ob.hz};
    double t_near = -kInf, t_far = kInf;
    int entry = 0;
    for (int a = 0; a < 3; ++a) {
      if (dl[a] == 0.0) {
        if (std::abs(l[a]) > h[a]) return false;
        continue;
      }
      const double inv = 1.0 / dl[a];
      const double t_lo = (-h[a] - l[a]) * inv, t_hi = (h[a] - l[a]) * inv;
      const double t_in = dl[a] > 0.0 ? t_lo : t_hi, t_out = dl[a] > 0.0 ? t_hi : t_lo;
      if (t_in > t_near) {
        t_near = t_in;
        entry = 2 * a + (dl[a] > 0.0 ? 1 : 0);  // entering through -h is the negative face
      }
      t_far = std::min(t_far, t_out);
    }
    if (t_near > t_far || t_near <= t_min || t_near >= t_best) return false;
    t_best = t_near;
    face = static_cast<std::uint8_t>(entry);
    return true;
  }
  if (ob.shape == SceneObject::Shape::sphere) {
    const double r = ob.hx;
    const double a = dx * dx + dy * dy + dz * dz, b = rx * dx + ry * dy + rz * dz;
    const double c = rx * rx + ry * ry + rz * rz - r * r;
    const double disc = b * b - a * c;
    if (disc < 0.0) return false;
    const double t = (-b - std::sqrt(disc)) / a;
    if (t <= t_min || t >= t_best) return false;
    t_best = t;
    face = 0;
    return true;
  }
  bool hit = false;
  const double r = ob.hx;
  const double a = dx * dx + dz * dz, b = rx * dx + rz * dz, c = rx * rx + rz * rz - r * r;
  if (a > 0.0) {
    const double disc = b * b - a * c;
    if (disc >= 0.0) {
      const double t = (-b - std::sqrt(disc)) / a;
      if (t > t_min && t < t_best && std::abs(ry + t * dy) <= ob.hy) {
        t_best = t;
        face = 0;
        hit = true;
      }
    }
  }
  if (dy > 0.0) {  // top cap, seen from above
    const double t = (ob.cy - ob.hy - oy) / dy;
    if (t > t_min && t < t_best) {
      const double qx = rx + t * dx, qz = rz + t * dz;
      if (qx * qx + qz * qz <= r * r) {
        t_best = t;
        face = 1;
        hit = true;
      }
    }
  }
  return hit;
}

SurfacePoint object_surface(const SceneObject& ob, double ground_y, std::uint8_t face, const Eigen::Vector3d& p) {
  SurfacePoint s;
  s.kind = ob.kind;
  s.seed = ob.seed;
  s.face = face;
  const double rx = p.x() - ob.cx, rz = p.z() - ob.cz;
  const double height = ground_y - p.y();
  const double top = ground_y - (ob.cy - ob.hy);
  if (ob.shape == SceneObject::Shape::sphere) {
    const Eigen::Vector3d n = (p - Eigen::Vector3d(ob.cx, ob.cy, ob.cz)) / ob.hx;
    s.u = (std::atan2(rz, rx) + std::numbers::pi) * ob.hx;
    s.v = height;
    s.extent_u = 2.0 * std::numbers::pi * ob.hx;
    s.extent_v = top;
    s.normal = n;
    return s;
  }
  if (ob.shape == SceneObject::Shape::cylinder) {
    if (face == 0) {
      s.u = (std::atan2(rz, rx) + std::numbers::pi) * ob.hx;
      s.v = height;
      s.extent_u = 2.0 * std::numbers::pi * ob.hx;
      s.extent_v = top;
      s.normal = Eigen::Vector3d(rx, 0.0, rz).normalized();
    } else {
      s.u = rx + ob.hx;
      s.v = rz + ob.hx;
      s.extent_u = s.extent_v = 2.0 * ob.hx;
      s.normal = -Eigen::Vector3d::UnitY();
    }
    return s;
  }
  const double lx = rx * ob.ax + rz * ob.az, lz = -rx * ob.az + rz * ob.ax;
  const Eigen::Vector3d axis_x(ob.ax, 0.0, ob.az), axis_z(-ob.az, 0.0, ob.ax);
  s.extent_v = top;
  switch (face) {
    case 0: s.u = ob.hz - lz; s.v = height; s.extent_u = 2.0 * ob.hz; s.normal = axis_x; break;
    case 1: s.u = ob.hz + lz; s.v = height; s.extent_u = 2.0 * ob.hz; s.normal = -axis_x; break;
    case 2:
    case 3:
      s.u = ob.hx + lx;
      s.v = ob.hz + lz;
      s.extent_u = 2.0 * ob.hx;
      s.extent_v = 2.0 * ob.hz;
      s.normal = face == 2 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d(-Eigen::Vector3d::UnitY());
      break;
    case 4: s.u = ob.hx + lx; s.v = height; s.extent_u = 2.0 * ob.hx; s.normal = axis_z; break;
    default: s.u = ob.hx - lx; s.v = height; s.extent_u = 2.0 * ob.hx; s.normal = -axis_z; break;
  }
  return s;
}

bool GroundDecal::contains(double x, double z) const {
  const double rx = x - cx, rz = z - cz;
  return std::abs(rx * ax + rz * az) <= half_length && std::abs(-rx * az + rz * ax) <= half_width;
}

StreetScene::StreetScene(const DrivePath& path, const StreetOptions& options, std::uint64_t seed, double s_begin,
                         double s_end)
    : ground_y_(options.camera_height) {
  options.validate();
  if (path.closed()) {
    s_begin = 0.0;
    s_end = path.length();
  }
  require(s_end > s_begin, "scene.s_end", "a range with s_end > s_begin");
  Rng rng(seed);
  const StreetOptions& o = options;
  const double centre = -o.lane_offset;  // lateral position of the road's centreline
  const double kerb[2] = {centre + o.road_half_width, centre - o.road_half_width};  // right, left
  const double lane_edge[2] = {kerb[0] - o.parking_width, kerb[1] + o.parking_width};
  const double side_sign[2] = {1.0, -1.0};
  const RoadClearance clearance(path, centre, s_begin - 30.0, s_end + 30.0);

  // Road surface and markings (chord pieces; short enough that the chords follow the bends).
  std::vector<GroundDecal> markings, surface;
  for_each_chord(path, s_begin - 10.0, s_end + 10.0, 1.5, centre, [&](const auto& a, const auto& b) {
    surface.push_back(chord_decal(SurfaceKind::road, a, b, o.road_half_width, 0.3));
  });
  for (int side = 0; side < 2; ++side) {
    if (o.parking_width > 0.0) {
      for_each_chord(path, s_begin - 10.0, s_end + 10.0, 1.5, lane_edge[side], [&](const auto& a, const auto& b) {
        markings.push_back(chord_decal(SurfaceKind::marking, a, b, 0.06, 0.02));
      });
      // Parking bay separators, every 6 m.
      for (double s = s_begin + rng.uniform(0.0, 6.0); s < s_end; s += 6.0) {
        const Eigen::Vector2d a = path.point(s, lane_edge[side]);
        const Eigen::Vector2d b = path.point(s, kerb[side] - side_sign[side] * 0.3);
        markings.push_back(chord_decal(SurfaceKind::marking, a, b, 0.05, 0.0));
      }
    }
  }
  for (double s = s_begin + rng.uniform(0.0, 9.0); s < s_end + 10.0; s += 9.0) {  // dashed centreline
    for_each_chord(path, s, s + 3.0, 1.5, centre, [&](const auto& a, const auto& b) {
      markings.push_back(chord_decal(SurfaceKind::marking, a, b, 0.06, 0.0));
    });
  }
  for (double s = s_begin + rng.uniform(20.0, 60.0); s < s_end; s += rng.uniform(70.0, 140.0)) {  // zebra crossings
    const PathPoint p = path.at(s + 1.5);
    for (double lat = lane_edge[1] + 0.5; lat < lane_edge[0] - 0.4; lat += 1.0) {
      const Eigen::Vector2d c = Eigen::Vector2d(p.x, p.z) + lat * p.right();
      GroundDecal g;
      g.kind = SurfaceKind::marking;
      g.cx = c.x();
      g.cz = c.y();
      g.ax = p.forward().x();
      g.az = p.forward().y();
      g.half_length = 1.5;
      g.half_width = 0.25;
      markings.push_back(g);
    }
  }
  decals_ = std::move(markings);
  decals_.insert(decals_.end(), surface.begin(), surface.end());

  // Building blocks along both sides; the chord of a block must not cut into the sidewalk's inner half.
  const double facade_clear = o.road_half_width + 0.5 * o.sidewalk_width;
  for (int side = 0; side < 2; ++side) {
    const double lateral = kerb[side] + side_sign[side] * o.sidewalk_width;
    double s = s_begin - 20.0 - rng.uniform(0.0, 10.0);
    if (path.closed()) s = s_begin + rng.uniform(0.0, 5.0);
    const double s_stop = path.closed() ? s_end : s_end + 20.0;
    while (s < s_stop) {
      double len = rng.uniform(o.building_min_length, o.building_max_length);
      // Keep blocks short in bends, where a long chord would leave the curved street.
      while (len > 6.0 && std::abs(path.at(s + len).heading - path.at(s).heading) > 0.3) len *= 0.8;
      const double gap = rng.uniform() < 0.35 ? 0.0 : rng.uniform(0.5, o.building_max_gap);
      const double depth = rng.uniform(8.0, 16.0);
      const double height = rng.uniform(o.building_min_height, o.building_max_height);
      const std::uint32_t bseed = rng.next32();
      const Eigen::Vector2d a = path.point(s, lateral), b = path.point(s + len, lateral);
      s += len + gap;
      const Eigen::Vector2d chord = b - a;
      if (chord.norm() < 3.0) continue;
      const Eigen::Vector2d axis = chord.normalized();
      Eigen::Vector2d outward(-axis.y(), axis.x());
      const PathPoint mid = path.at(s - gap - 0.5 * len);
      if (outward.dot(mid.right()) * side_sign[side] < 0.0) outward = -outward;
      Eigen::Vector2d c = 0.5 * (a + b) + 0.5 * depth * outward;
      SceneObject box = upright_box(SurfaceKind::facade, bseed, c, axis, 0.5 * chord.norm(), 0.5 * depth, ground_y_,
                                    0.0, height);
      double deficit = facade_clear - clearance.distance(footprint(box));
      if (deficit > 0.0) {  // bend: push the block back from the road
        c += (deficit + 0.05) * outward;
        box.cx = c.x();
        box.cz = c.y();
        deficit = facade_clear - clearance.distance(footprint(box));
      }
      if (deficit > 0.0) continue;  // e.g. the inside of a tight corner: leave the lot empty
      objects_.push_back(box);
    }
  }

  // Parked cars (body and cabin) in the parking lanes, containers on the sidewalk.
  const double lane_clear = o.road_half_width - o.parking_width - 0.05;
  for (int side = 0; side < 2; ++side) {
    for (double s = s_begin - 10.0 + rng.uniform(0.0, 3.0); s < s_end + 10.0;) {
      const double slot = rng.uniform(5.3, 6.5);
      const bool taken = rng.uniform() < o.parked_probability;
      const bool container = rng.uniform() < o.container_probability;
      const double body_h = rng.uniform(0.75, 0.95), cabin_h = rng.uniform(0.42, 0.55);
      const double len = container ? 6.06 : rng.uniform(3.9, 4.8);
      const double width = container ? 2.44 : rng.uniform(1.7, 1.9);
      const std::uint32_t cseed = rng.next32();
      const PathPoint p = path.at(s + 0.5 * slot);
      s += slot;
      if (!taken) continue;
      if (container && side == 0 && o.hedge_height > 0.0) continue;  // the hedge stands there
      const double lat = container ? kerb[side] + side_sign[side] * (0.3 + 0.5 * width)
                                   : kerb[side] - side_sign[side] * (0.15 + 0.5 * width);
      const Eigen::Vector2d c = Eigen::Vector2d(p.x, p.z) + lat * p.right();
      if (container) {
        SceneObject box = upright_box(SurfaceKind::container, cseed, c, p.forward(), 0.5 * len, 0.5 * width, ground_y_,
                                      0.0, 2.59);
        if (clearance.distance(footprint(box)) < o.road_half_width + 0.1) continue;
        objects_.push_back(box);
        continue;
      }
      SceneObject body = upright_box(SurfaceKind::car, cseed, c, p.forward(), 0.5 * len, 0.5 * width, ground_y_, 0.0,
                                     body_h);
      if (clearance.distance(footprint(body)) < lane_clear) continue;
      const double cabin_len = len * rng.uniform(0.48, 0.6);
      const Eigen::Vector2d cabin_c = c - 0.08 * len * p.forward();
      objects_.push_back(body);
      objects_.push_back(upright_box(SurfaceKind::cabin, cseed, cabin_c, p.forward(), 0.5 * cabin_len,
                                     0.5 * width - 0.1, ground_y_, body_h, body_h + cabin_h));
    }
  }

  // Poles (some with a sign facing the oncoming traffic) and bollards near the kerbs; bins at facades.
  for (int side = 0; side < 2; ++side) {
    for (double s = s_begin - 10.0 + rng.uniform(0.0, o.pole_spacing); s < s_end + 10.0;
         s += o.pole_spacing * rng.uniform(0.6, 1.4)) {
      const PathPoint p = path.at(s);
      const double radius = rng.uniform(0.06, 0.14), height = rng.uniform(3.5, 8.0);
      const bool sign = rng.uniform() < 0.45;
      const std::uint32_t pseed = rng.next32();
      if (side == 0 && o.hedge_height > 0.0) continue;
      const Eigen::Vector2d c = Eigen::Vector2d(p.x, p.z) + (kerb[side] + side_sign[side] * 0.45) * p.right();
      const SceneObject pole = cylinder(SurfaceKind::pole, pseed, c, radius, ground_y_, height);
      if (clearance.distance(footprint(pole)) < o.road_half_width + 0.1) continue;
      objects_.push_back(pole);
      if (sign) {
        const Eigen::Vector2d sc = c - (radius + 0.03) * p.forward();
        objects_.push_back(upright_box(SurfaceKind::sign, pseed ^ 0x1234567U, sc, p.forward(), 0.025, 0.35, ground_y_,
                                       height - 0.9, height - 0.2));
      }
      // A bollard or a bin a few metres on.
      const PathPoint q = path.at(s + rng.uniform(3.0, 6.0));
      const std::uint32_t qseed = rng.next32();
      if (rng.uniform() < 0.5) {
        const Eigen::Vector2d bc = Eigen::Vector2d(q.x, q.z) + (kerb[side] + side_sign[side] * 0.35) * q.right();
        const SceneObject bollard = cylinder(SurfaceKind::pole, qseed, bc, 0.09, ground_y_, 0.95);
        if (clearance.distance(footprint(bollard)) >= o.road_half_width + 0.1) objects_.push_back(bollard);
      } else {
        const double lat = kerb[side] + side_sign[side] * (o.sidewalk_width - 0.5);
        const Eigen::Vector2d bc = Eigen::Vector2d(q.x, q.z) + lat * q.right();
        const SceneObject bin = upright_box(SurfaceKind::container, qseed, bc, q.forward(), 0.35, 0.35, ground_y_, 0.0,
                                            rng.uniform(0.9, 1.3));
        if (clearance.distance(footprint(bin)) >= o.road_half_width + 0.1) objects_.push_back(bin);
      }
    }
  }
  // Trees on the sidewalks: a trunk and a round crown that may reach over the parking lane.
  for (int side = 0; side < 2; ++side) {
    for (double s = s_begin - 10.0 + rng.uniform(0.0, o.tree_spacing); s < s_end + 10.0;
         s += o.tree_spacing * rng.uniform(0.6, 1.4)) {
      const PathPoint p = path.at(s);
      const double trunk_r = rng.uniform(0.12, 0.22), trunk_h = rng.uniform(2.6, 3.6), crown_r = rng.uniform(1.3, 2.3);
      const std::uint32_t tseed = rng.next32();
      if (side == 0 && o.hedge_height > 0.0) continue;
      const Eigen::Vector2d c = Eigen::Vector2d(p.x, p.z) + (kerb[side] + side_sign[side] * o.tree_offset) * p.right();
      const SceneObject trunk = cylinder(SurfaceKind::bark, tseed, c, trunk_r, ground_y_, trunk_h + 0.5 * crown_r);
      if (clearance.distance(footprint(trunk)) < o.road_half_width + 0.5) continue;
      SceneObject crown;
      crown.shape = SceneObject::Shape::sphere;
      crown.kind = SurfaceKind::foliage;
      crown.seed = tseed;
      crown.cx = c.x();
      crown.cz = c.y();
      crown.cy = ground_y_ - trunk_h - 0.8 * crown_r;
      crown.hx = crown.hy = crown.hz = crown_r;
      // keep the crown above the parking lane and out of the driving lanes' space
      if (clearance.distance(footprint(crown)) < lane_clear) continue;
      objects_.push_back(trunk);
      objects_.push_back(crown);
    }
  }
  // The hedge: pieces of 2.5-4.5 m along the right kerb, each of its own height, so that its top edge
  // is ragged; its own random source keeps the rest of the street as without it.
  if (o.hedge_height > 0.0) {
    Rng hedge_rng(seed ^ 0x4ED6EULL);
    const double near = kerb[0] + o.hedge_offset, mid = near + 0.5 * o.hedge_depth;
    for (double s = s_begin - 10.0; s < s_end + 10.0;) {
      const double len = hedge_rng.uniform(2.5, 4.5);
      const double height = o.hedge_height * hedge_rng.uniform(0.85, 1.15);
      const std::uint32_t hseed = hedge_rng.next32();
      const Eigen::Vector2d a = path.point(s, mid), b = path.point(s + len, mid);
      s += len;
      const Eigen::Vector2d chord = b - a;
      // overlap the neighbours a little so that no gap opens in bends
      objects_.push_back(upright_box(SurfaceKind::foliage, hseed, 0.5 * (a + b), chord.normalized(),
                                     0.5 * chord.norm() + 0.05, 0.5 * o.hedge_depth, ground_y_, 0.0, height));
    }
  }
  if (o.repeat_length > 0.0) repeat_blocks(path, s_begin, s_end, o.repeat_length);
  build_grid();
}

void StreetScene::repeat_blocks(const DrivePath& path, double s_begin, double s_end, double period) {
  const PathPoint start = path.at(s_begin);
  require(!path.closed() && path.at(s_end).heading == start.heading &&
              path.at(0.5 * (s_begin + s_end)).heading == start.heading,
          "scene.repeat_length", "a straight path (blocks repeat by translation)");
  const Eigen::Vector2d forward = start.forward(), origin(start.x, start.z);
  const auto along = [&](double x, double z) { return (Eigen::Vector2d(x, z) - origin).dot(forward); };
  // The block: objects wholly inside [0, period) along the street, markings centred there.
  std::vector<SceneObject> block;
  for (const SceneObject& ob : objects_) {
    const double reach = std::abs(ob.ax * forward.x() + ob.az * forward.y()) * ob.hx +
                         std::abs(-ob.az * forward.x() + ob.ax * forward.y()) * ob.hz;
    const double a = along(ob.cx, ob.cz);
    if (a - reach >= 0.0 && a + reach < period) block.push_back(ob);
  }
  std::vector<GroundDecal> markings, surface;
  for (const GroundDecal& d : decals_) {
    if (d.kind != SurfaceKind::marking) {
      surface.push_back(d);
    } else if (const double a = along(d.cx, d.cz); a >= 0.0 && a < period) {
      markings.push_back(d);
    }
  }
  objects_.clear();
  decals_.clear();
  const int last = static_cast<int>(std::ceil((s_end - s_begin) / period)) + 1;
  for (int k = -1; k <= last; ++k) {
    const Eigen::Vector2d shift = k * period * forward;
    for (SceneObject ob : block) {
      ob.cx += shift.x();
      ob.cz += shift.y();
      objects_.push_back(ob);
    }
    for (GroundDecal d : markings) {
      d.cx += shift.x();
      d.cz += shift.y();
      decals_.push_back(d);
    }
  }
  decals_.insert(decals_.end(), surface.begin(), surface.end());  // markings first
}

StreetScene::StreetScene(std::vector<SceneObject> objects, std::vector<GroundDecal> decals, double ground_y)
    : objects_(std::move(objects)), decals_(std::move(decals)), ground_y_(ground_y) {
  std::stable_partition(decals_.begin(), decals_.end(),
                        [](const GroundDecal& d) { return d.kind == SurfaceKind::marking; });
  build_grid();
}

void StreetScene::build_grid() {
  double xmin = kInf, xmax = -kInf, zmin = kInf, zmax = -kInf;
  top_y_ = ground_y_;
  auto grow = [&](const Footprint& f) {
    double a, b, c, d;
    bounds(f, a, b, c, d);
    xmin = std::min(xmin, a);
    xmax = std::max(xmax, b);
    zmin = std::min(zmin, c);
    zmax = std::max(zmax, d);
  };
  for (const auto& o : objects_) {
    grow(footprint(o));
    top_y_ = std::min(top_y_, o.cy - o.hy);
  }
  for (const auto& d : decals_) grow(footprint(d));
  if (!(xmin < xmax)) {  // empty scene: one cell at the origin
    xmin = zmin = -1.0;
    xmax = zmax = 1.0;
  }
  x0_ = xmin - cell_;
  z0_ = zmin - cell_;
  nx_ = static_cast<int>(std::ceil((xmax - xmin) / cell_)) + 2;
  nz_ = static_cast<int>(std::ceil((zmax - zmin) / cell_)) + 2;
  const auto cells = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(nz_);

  // Two passes per list (count, then fill) into CSR arrays.
  auto fill = [&](auto const& items, std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& index) {
    std::vector<std::vector<std::uint32_t>> lists(cells);
    for (std::size_t i = 0; i < items.size(); ++i) {
      const Footprint f = footprint(items[i]);
      double a, b, c, d;
      bounds(f, a, b, c, d);
      const int ix0 = std::max(0, static_cast<int>(std::floor((a - x0_) / cell_)));
      const int ix1 = std::min(nx_ - 1, static_cast<int>(std::floor((b - x0_) / cell_)));
      const int iz0 = std::max(0, static_cast<int>(std::floor((c - z0_) / cell_)));
      const int iz1 = std::min(nz_ - 1, static_cast<int>(std::floor((d - z0_) / cell_)));
      for (int iz = iz0; iz <= iz1; ++iz) {
        for (int ix = ix0; ix <= ix1; ++ix) {
          if (!overlaps_cell(f, x0_ + ix * cell_, z0_ + iz * cell_, cell_)) continue;
          lists[static_cast<std::size_t>(iz) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ix)].push_back(
              static_cast<std::uint32_t>(i));
        }
      }
    }
    start.assign(cells + 1, 0);
    index.clear();
    for (std::size_t c = 0; c < cells; ++c) {
      start[c] = static_cast<std::uint32_t>(index.size());
      index.insert(index.end(), lists[c].begin(), lists[c].end());
    }
    start[cells] = static_cast<std::uint32_t>(index.size());
  };
  fill(objects_, object_start_, object_index_);
  cell_top_.assign(cells, kInf);
  for (std::size_t c = 0; c < cells; ++c) {
    for (std::uint32_t k = object_start_[c]; k < object_start_[c + 1]; ++k) {
      const SceneObject& o = objects_[object_index_[k]];
      cell_top_[c] = std::min(cell_top_[c], o.cy - o.hy);
    }
  }
  fill(decals_, decal_start_, decal_index_);
}

std::optional<RayHit> StreetScene::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                             double t_max, double t_min) const {
  const double ox = origin.x(), oy = origin.y(), oz = origin.z();
  const double dx = direction.x(), dy = direction.y(), dz = direction.z();
  double t_end = t_max;
  bool ground = false;
  double t_ground = kInf;
  if (dy > 0.0) {
    t_ground = (ground_y_ - oy) / dy;
    if (t_ground > t_min && t_ground <= t_end) {
      t_end = t_ground;
      ground = true;
    }
  } else if (dy < 0.0) {
    // Going up: past the highest roof nothing can be hit.
    t_end = std::min(t_end, (top_y_ - oy) / dy);
  }
  double best = t_end;
  std::uint32_t best_object = kGround;
  std::uint8_t best_face = 0;

  // Clip the ray's ground-plane projection to the grid.
  double ta = t_min, tb = t_end;
  const double x1 = x0_ + nx_ * cell_, z1 = z0_ + nz_ * cell_;
  auto clip = [&](double o, double d, double lo, double hi) {
    if (d == 0.0) {
      if (o < lo || o > hi) tb = -kInf;
      return;
    }
    const double t1 = (lo - o) / d, t2 = (hi - o) / d;
    ta = std::max(ta, std::min(t1, t2));
    tb = std::min(tb, std::max(t1, t2));
  };
  clip(ox, dx, x0_, x1);
  clip(oz, dz, z0_, z1);
  const bool above_roofs = dy <= 0.0 && oy < top_y_;
  if (ta <= tb && !above_roofs) {
    const double px = ox + ta * dx, pz = oz + ta * dz;
    int ix = std::clamp(static_cast<int>(std::floor((px - x0_) / cell_)), 0, nx_ - 1);
    int iz = std::clamp(static_cast<int>(std::floor((pz - z0_) / cell_)), 0, nz_ - 1);
    const int step_x = dx > 0.0 ? 1 : -1, step_z = dz > 0.0 ? 1 : -1;
    double next_x = dx != 0.0 ? (x0_ + (ix + (dx > 0.0 ? 1 : 0)) * cell_ - ox) / dx : kInf;
    double next_z = dz != 0.0 ? (z0_ + (iz + (dz > 0.0 ? 1 : 0)) * cell_ - oz) / dz : kInf;
    const double delta_x = dx != 0.0 ? cell_ / std::abs(dx) : kInf;
    const double delta_z = dz != 0.0 ? cell_ / std::abs(dz) : kInf;
    // Objects spanning several cells are tested once: a small list of the ones already tried.
    std::array<std::uint32_t, 24> tried{};
    std::size_t n_tried = 0;
    double cell_t_in = ta;
    while (true) {
      const auto cell = static_cast<std::size_t>(iz) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ix);
      const double cell_t_out = std::min({next_x, next_z, tb});
      // Lowest point (largest y) of the ray inside this cell: above the cell's highest top, skip it.
      const double lowest_y = oy + (dy > 0.0 ? cell_t_out : cell_t_in) * dy;
      const bool reachable = lowest_y >= cell_top_[cell];
      for (std::uint32_t k = reachable ? object_start_[cell] : object_start_[cell + 1]; k < object_start_[cell + 1]; ++k) {
        const std::uint32_t id = object_index_[k];
        const SceneObject& ob = objects_[id];
        if (ob.hx > 0.5 * cell_ || ob.hz > 0.5 * cell_) {
          if (std::find(tried.begin(), tried.begin() + static_cast<std::ptrdiff_t>(n_tried), id) !=
              tried.begin() + static_cast<std::ptrdiff_t>(n_tried)) {
            continue;
          }
          if (n_tried < tried.size()) tried[n_tried++] = id;
        }
        if (intersect_object(ob, origin, direction, t_min, best, best_face)) best_object = id;
      }
      const double t_exit = std::min(next_x, next_z);
      if (best <= t_exit || t_exit >= tb) break;
      cell_t_in = t_exit;
      if (next_x < next_z) {
        ix += step_x;
        if (ix < 0 || ix >= nx_) break;
        next_x += delta_x;
      } else {
        iz += step_z;
        if (iz < 0 || iz >= nz_) break;
        next_z += delta_z;
      }
    }
  }
  if (best_object != kGround) return RayHit{best, best_object, best_face};
  if (ground) return RayHit{t_ground, kGround, 0};
  return std::nullopt;
}

SurfaceKind StreetScene::ground_kind(double x, double z) const {
  const int ix = static_cast<int>(std::floor((x - x0_) / cell_));
  const int iz = static_cast<int>(std::floor((z - z0_) / cell_));
  if (ix < 0 || iz < 0 || ix >= nx_ || iz >= nz_) return SurfaceKind::sidewalk;
  const auto cell = static_cast<std::size_t>(iz) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ix);
  for (std::uint32_t k = decal_start_[cell]; k < decal_start_[cell + 1]; ++k) {
    const GroundDecal& d = decals_[decal_index_[k]];
    if (d.contains(x, z)) return d.kind;
  }
  return SurfaceKind::sidewalk;
}

SurfacePoint StreetScene::surface(const RayHit& hit, const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& direction) const {
  const Eigen::Vector3d p = origin + hit.t * direction;
  SurfacePoint s;
  if (hit.object == kGround) {
    s.kind = ground_kind(p.x(), p.z());
    s.u = p.x();
    s.v = p.z();
    s.normal = -Eigen::Vector3d::UnitY();
    return s;
  }
  return object_surface(objects_[hit.object], ground_y_, hit.face, p);
}

double StreetScene::signed_distance(const Eigen::Vector3d& p) const {
  double d = ground_y_ - p.y();
  for (const auto& ob : objects_) {
    switch (ob.shape) {
      case SceneObject::Shape::box: d = std::min(d, box_sdf(ob, p)); break;
      case SceneObject::Shape::cylinder: d = std::min(d, cylinder_sdf(ob, p)); break;
      case SceneObject::Shape::sphere: d = std::min(d, (p - Eigen::Vector3d(ob.cx, ob.cy, ob.cz)).norm() - ob.hx); break;
    }
  }
  return d;
}

}  // namespace rgbl
