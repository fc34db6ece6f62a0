#pragma once
// The synthetic street: a flat textured road with markings, sidewalks, building blocks along both
// sides, parked cars and containers, poles with signs, trees. Geometry is analytic (the ground plane,
// boxes that stand upright with any yaw, vertical cylinders, spheres), so rays hit it exactly.
//
// Texture is a function of the surface point alone (the object's own face coordinates, or world x/z
// on the ground), so one surface point has the same colour from every view. Detail finer than a
// sample's footprint is replaced by its mean (a simple level of detail against aliasing).

#include "rgbl/sim/path.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

namespace rgbl {

enum class SurfaceKind : std::uint8_t { road, marking, sidewalk, facade, car, cabin, container, pole, sign, bark, foliage };

struct StreetOptions {
  double camera_height = 1.65;    // m, cam0 above the road (the road is the plane y = camera_height)
  double lane_offset = 1.65;      // m, camera track to the right of the road's centreline
  double road_half_width = 5.5;   // m, centreline to kerb: a 3.3 m lane plus a 2.2 m parking lane
  double parking_width = 2.2;     // m
  double sidewalk_width = 3.0;    // m, kerb to facade
  double building_min_length = 10.0, building_max_length = 28.0;  // m along the street
  double building_min_height = 7.0, building_max_height = 22.0;   // m
  double building_max_gap = 5.0;  // m between neighbouring blocks
  double parked_probability = 0.6;     // share of parking slots taken by a car or container
  double container_probability = 0.12; // share of the taken slots holding a container
  double pole_spacing = 16.0;     // m, mean distance between poles along each kerb
  double tree_spacing = 14.0;     // m, mean distance between trees along each sidewalk
  double tree_offset = 1.3;       // m, kerb to the trunks (crowns that would reach the driving lanes are left out)
  // A dense hedge along the right kerb instead of poles, trees and bins on that sidewalk (0 = none).
  double hedge_height = 0.0;      // m, mean height (it varies by +-15 % from piece to piece)
  double hedge_offset = 0.3;      // m, kerb to the hedge's road-side face
  double hedge_depth = 1.2;       // m
  // A street of identical blocks (0 = none): what stands wholly within the first repeat_length metres,
  // and the markings there, are copied every repeat_length metres with their seeds, so every block
  // looks and scans exactly like the others (only the asphalt's texture follows the world). A straight
  // path only. Built to tempt place recognition into a false loop.
  double repeat_length = 0.0;     // m

  void validate() const;
};

// A ray's first hit, before shading.
struct RayHit {
  double t = 0.0;               // ray parameter: the hit point is origin + t * direction
  std::uint32_t object = 0;     // index into the scene's objects, or StreetScene::kGround
  std::uint8_t face = 0;        // box face 0..5 (+x, -x, +y, -y, +z, -z local); cylinder 0 side, 1 top; sphere 0
};

// What a hit point looks like: where it is on its surface.
struct SurfacePoint {
  SurfaceKind kind = SurfaceKind::road;
  std::uint32_t seed = 0;   // the object's seed (0 on the ground)
  std::uint8_t face = 0;    // as in RayHit
  double u = 0.0, v = 0.0;  // surface coordinates, metres (v = height above the road on walls)
  double extent_u = 0.0, extent_v = 0.0;  // the face's size: u in [0, extent_u], v up to extent_v
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // world, outward
};

// A shape of the street: a box with vertical sides and any yaw, a vertical cylinder, or a sphere
// (a tree's crown).
struct SceneObject {
  enum class Shape : std::uint8_t { box, cylinder, sphere };
  Shape shape = Shape::box;
  SurfaceKind kind = SurfaceKind::facade;
  std::uint32_t seed = 0;
  double cx = 0.0, cy = 0.0, cz = 0.0;  // centre, world
  double ax = 1.0, az = 0.0;            // unit local x axis in world (x, z); local z is (-az, ax)
  double hx = 0.0, hy = 0.0, hz = 0.0;  // half extents along local x, y, z (cylinder: radius, half height, radius;
                                        // sphere: the radius thrice)
};

// A flat mark on the road (asphalt, a painted line): an oriented rectangle in the ground plane.
struct GroundDecal {
  SurfaceKind kind = SurfaceKind::road;
  double cx = 0.0, cz = 0.0;     // centre (world x, z)
  double ax = 1.0, az = 0.0;     // unit long axis (x, z)
  double half_length = 0.0, half_width = 0.0;

  bool contains(double x, double z) const;
};

// Surface coordinates and outward normal of a hit on one object (not the ground) at world point p;
// the road is the plane y = ground_y.
SurfacePoint object_surface(const SceneObject& object, double ground_y, std::uint8_t face, const Eigen::Vector3d& p);

// Ray origin + t * direction against one object: when it hits at t_min < t < t_best, sets t_best and
// face and returns true.
bool intersect_object(const SceneObject& object, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      double t_min, double& t_best, std::uint8_t& face);

class StreetScene {
 public:
  static constexpr std::uint32_t kGround = 0xFFFFFFFFU;

  // Lays the street out along `path` for arc lengths [s_begin, s_end] (a closed path: all of it).
  StreetScene(const DrivePath& path, const StreetOptions& options, std::uint64_t seed, double s_begin, double s_end);
  // A scene from explicit parts (for tests and custom scenes); the ground is sidewalk outside decals.
  StreetScene(std::vector<SceneObject> objects, std::vector<GroundDecal> decals, double ground_y);

  // First hit of origin + t * direction with t in (t_min, t_max]; direction need not be unit length.
  std::optional<RayHit> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_max, double t_min = 1e-6) const;
  // Surface coordinates and outward normal of a hit.
  SurfacePoint surface(const RayHit& hit, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;

  // Signed distance of a point to the scene's surfaces (negative inside an object or below the road),
  // computed independently of the ray caster: for checking hits.
  double signed_distance(const Eigen::Vector3d& p) const;

  double ground_y() const { return ground_y_; }
  const std::vector<SceneObject>& objects() const { return objects_; }
  const std::vector<GroundDecal>& decals() const { return decals_; }

 private:
  void build_grid();
  void repeat_blocks(const DrivePath& path, double s_begin, double s_end, double period);
  SurfaceKind ground_kind(double x, double z) const;

  std::vector<SceneObject> objects_;
  std::vector<GroundDecal> decals_;   // markings first: the first decal containing a point wins
  double ground_y_ = 0.0;
  double top_y_ = 0.0;                // y of the highest object top (smallest y)

  // Uniform grid over world x/z: per cell the objects and decals that overlap it (CSR layout).
  double cell_ = 4.0;
  double x0_ = 0.0, z0_ = 0.0;
  int nx_ = 0, nz_ = 0;
  std::vector<std::uint32_t> object_start_, object_index_;
  std::vector<std::uint32_t> decal_start_, decal_index_;
  std::vector<double> cell_top_;      // per cell: y of its highest object top (+inf when empty)
};

}  // namespace rgbl
