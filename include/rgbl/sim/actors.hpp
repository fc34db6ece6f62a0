#pragma once
// Moving vehicles of the synthetic street. An actor is a few upright boxes (a car's body and cabin, a
// truck's cab and cargo box) that drive along the camera's path at a lateral offset, with or against
// the camera's direction, at their own speed profile. At any time they become ordinary scene boxes,
// intersected together with the static street for images, LiDAR scans and exact depth; their texture
// is in their own face coordinates, so it moves with them.

#include "rgbl/sim/path.hpp"
#include "rgbl/sim/scene.hpp"

#include <cstdint>
#include <vector>

namespace rgbl {

// One box of an actor, in the actor's frame: x forward from its reference point, heights above the road.
struct ActorPart {
  SurfaceKind kind = SurfaceKind::car;
  double back = -2.0, front = 2.0;  // m along the actor's forward axis, back < front
  double half_width = 0.9;          // m
  double bottom = 0.0, top = 1.0;   // m above the road, bottom < top
};

enum class VehicleKind : std::uint8_t { car, van, truck };

struct Actor {
  std::uint32_t seed = 0;        // look (paint, plates, labels)
  std::vector<ActorPart> parts;
  double lateral = 0.0;          // m right of the camera's track (the ego lane is 0)
  bool oncoming = false;         // drives against the camera's direction
  double s0 = 0.0;               // arc length of the reference point on the path at time 0
  double speed = 10.0;           // m/s at time 0
  std::vector<SpeedPhase> speed_phases;

  // Throws ConfigError naming `key` (e.g. "actors[2]").
  void validate(const char* key = "actors") const;
  double length() const;  // m, front of the foremost part to the back of the rearmost
};

// A vehicle of the given kind, its size and proportions drawn from `seed`.
Actor make_vehicle(VehicleKind kind, std::uint32_t seed);

// The boxes of all actors at time t (parts in order, actor by actor), placed on `path`.
std::vector<SceneObject> actor_boxes(const std::vector<Actor>& actors, const DrivePath& path, double ground_y,
                                     double t);

}  // namespace rgbl
