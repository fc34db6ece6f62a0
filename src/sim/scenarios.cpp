#include "rgbl/sim/scenarios.hpp"

#include "hash.hpp"
#include "rgbl/core/error.hpp"

#include <array>
#include <string>

namespace rgbl {
namespace {

using sim_detail::Rng;

// What every scenario shares: the look of KITTI's grey cameras at half resolution, tuned with
// rgbl_image_stats against sequence 04 and raw drive 0009 (docs/synthetic.md): a steeper tone curve
// (KITTI's sky is near white, its shadows near black), a slight lens blur, sensor noise, lower blocks
// (more sky).
void kitti_look(SyntheticOptions& o) {
  o.contrast = 1.45;
  o.lens_blur_sigma = 0.5;
  o.image_noise_sigma = 1.5;
  o.scene.building_min_height = 6.0;
  o.scene.building_max_height = 18.0;
}

// The reference street: the curve of the generator's defaults (the demo's street without --scenario),
// with the shared look.
void plain(SyntheticOptions&, Rng&) {}

// A van in the ego lane, 5.5-6.5 m ahead, at exactly the camera's speed for the whole run: it stands
// still in the image while the street streams past, and covers 10-25 % of it.
void lead_vehicle(SyntheticOptions& o, Rng& rng) {
  Actor van = make_vehicle(VehicleKind::van, rng.next32());
  van.s0 = rng.uniform(5.5, 6.5) + 0.5 * van.length();
  van.speed = o.speed;
  van.speed_phases = o.speed_phases;
  o.actors.push_back(van);
}

// Traffic in both directions on a four-lane street while the camera brakes to a stop, stands for two
// seconds and pulls away again.
void traffic(SyntheticOptions& o, Rng& rng) {
  o.scene.road_half_width = 6.6;  // two 3.3 m lanes each way, no parking lane
  o.scene.parking_width = 0.0;
  o.speed = 10.0;
  o.speed_phases = {{2.0, 0.0}, {10.0 / 3.5, -3.5}, {2.0, 0.0}, {4.0, 2.0}};
  struct Lane {
    double lateral;
    bool oncoming;
    double s_begin, s_end;
  };
  // the right lane passes the standing camera; the two oncoming lanes come towards it
  const std::array<Lane, 3> lanes{{{3.3, false, -45.0, 110.0}, {-3.3, true, -10.0, 190.0}, {-6.6, true, 0.0, 190.0}}};
  for (const Lane& lane : lanes) {
    const double speed = rng.uniform(9.0, 13.0);
    for (double s = lane.s_begin + rng.uniform(0.0, 10.0); s < lane.s_end;) {
      const double pick = rng.uniform();
      const VehicleKind kind = pick < 0.35 ? VehicleKind::truck : (pick < 0.55 ? VehicleKind::van : VehicleKind::car);
      Actor a = make_vehicle(kind, rng.next32());
      a.lateral = lane.lateral;
      a.oncoming = lane.oncoming;
      a.speed = speed;  // one speed per lane: nobody runs into the vehicle ahead
      a.s0 = s + 0.5 * a.length();
      o.actors.push_back(a);
      s += a.length() + rng.uniform(6.0, 22.0);
    }
  }
}

// A dense, self-similar hedge 2.25 m right of the camera (a narrow country-town street), trees on the
// left, motion blur from an 8 ms exposure, and LiDAR returns that sink into the leaves.
void foliage(SyntheticOptions& o, Rng&) {
  o.scene.road_half_width = 3.6;  // the ego lane and a narrow shoulder on the right
  o.scene.parking_width = 0.3;
  o.scene.hedge_height = 2.4;
  o.scene.hedge_offset = 0.3;
  o.scene.hedge_depth = 1.2;
  o.scene.tree_spacing = 7.0;
  o.scene.tree_offset = 2.3;  // crowns clear of the narrow road
  o.exposure_time = 0.008;
  o.lidar.foliage_penetration = 0.2;
}

// The sun 50 deg high from the front left: buildings, cars and trees cast hard shadows over part of
// the road and onto the facades, crowns dapple the light; the camera's auto exposure steps (+30 %,
// then -30 %) and drifts.
void shadows(SyntheticOptions& o, Rng& rng) {
  o.light.sun_direction = Eigen::Vector3d(-0.39, -0.77, 0.51);  // 50 deg high
  o.light.ambient = 0.5;
  o.light.sun = 0.95;
  o.light.cast_shadows = true;
  o.scene.tree_spacing = 9.0;
  const int first = 15 + static_cast<int>(rng.uniform(0.0, 6.0));
  o.exposure_steps = {{first, 1.3}, {first + 22, 0.7}};
  o.exposure_drift = 0.08;
  o.exposure_drift_period = 50.0;
}

// A junction: approach at 8 m/s, brake to 4.5 m/s, a 90 degree left turn of 12 m radius between
// buildings, then pull away.
void turn(SyntheticOptions& o, Rng&) {
  o.path.kind = PathKind::turn;
  o.path.turn_start = 21.0;
  o.path.turn_radius = 12.0;
  o.path.turn_angle_deg = 90.0;
  o.speed = 8.0;
  o.speed_phases = {{1.0, 0.0}, {1.75, -2.0}, {4.66, 0.0}, {3.0, 1.5}};
}

// The drive of issue 13 on which the tracker failed, re-created: a tree-lined street at 12 m/s with a
// hedge close on the right (blur, leaf LiDAR), leaf and building shadows, a car ahead that the camera
// closes in on and then follows at its own speed for the last 40 frames, a gentle curve at the end.
void suburban(SyntheticOptions& o, Rng& rng) {
  foliage(o, rng);
  o.light.sun_direction = Eigen::Vector3d(-0.39, -0.77, 0.51);
  o.light.ambient = 0.5;
  o.light.sun = 0.95;
  o.light.cast_shadows = true;
  o.exposure_drift = 0.06;
  o.exposure_drift_period = 70.0;
  o.speed = 12.0;
  o.path.bend_straight = 85.0;
  o.path.bend_radius = 80.0;
  o.path.bend_angle_deg = 25.0;
  // 42 m ahead at 6 m/s for 4 s (the gap closes to 18 m), then 3 m/s^2 for 2 s up to the camera's
  // 12 m/s: from 6 s on (frame 60) it stays 12 m ahead
  Actor car = make_vehicle(VehicleKind::car, rng.next32());
  car.s0 = 42.0 + 0.5 * car.length();
  car.speed = 6.0;
  car.speed_phases = {{4.0, 0.0}, {2.0, 3.0}};
  o.actors.push_back(car);
}

// A straight street of identical 100 m blocks (buildings, parked cars, poles, trees, markings; only the
// asphalt differs): every block scans and looks like the one before, so place recognition finds a
// convincing loop every 100 m that is not one. Three blocks.
void repeated(SyntheticOptions& o, Rng&) {
  o.path.kind = PathKind::straight;
  o.scene.repeat_length = 100.0;
}

struct Entry {
  ScenarioInfo info;
  void (*build)(SyntheticOptions&, Rng&);
};

constexpr std::array<Entry, 8> kScenarios{{
    {{"plain", "the reference street: 30 m straight, a gentle 60 deg bend (radius 40 m), 10 m/s", 60}, plain},
    {{"lead-vehicle", "a van 6 m ahead in the ego lane at the ego speed for the whole run (10-25 % of the image)", 60},
     lead_vehicle},
    {{"traffic", "cars and trucks in three other lanes, both directions; the ego brakes at 3.5 m/s^2 and stands 2 s", 80},
     traffic},
    {{"foliage", "a dense hedge 2.25 m to the right, trees on the left, 8 ms motion blur, LiDAR sinking into leaves", 60},
     foliage},
    {{"shadows", "sun from the front left: cast and dappled shadows on road and facades; exposure steps +-30 %, drift",
      60},
     shadows},
    {{"turn", "a 90 deg left turn of 12 m radius at 4.5 m/s between buildings, braking before, accelerating after", 85},
     turn},
    {{"suburban",
      "issue 13's failing drive: hedge, leaf shadows, blur, 12 m/s, a car 12 m ahead at ego speed for the last "
      "40 frames, a gentle curve",
      100},
     suburban},
    {{"repeated", "a straight street of identical 100 m blocks: a false loop every block for place recognition to refuse",
      300},
     repeated},
}};

}  // namespace

std::vector<ScenarioInfo> scenarios() {
  std::vector<ScenarioInfo> list;
  for (const Entry& e : kScenarios) list.push_back(e.info);
  return list;
}

SyntheticOptions scenario_options(std::string_view name, std::uint64_t seed, int frames) {
  for (const Entry& e : kScenarios) {
    if (e.info.name != name) continue;
    SyntheticOptions o;
    o.scenario = std::string(name);
    o.seed = seed;
    o.frames = frames > 0 ? frames : e.info.default_frames;
    o.path.kind = PathKind::curve;
    kitti_look(o);
    // the scenario's own draws (actors, event frames) from the seed and its name, apart from the street's
    std::uint64_t salt = 0;
    for (const char c : name) salt = sim_detail::mix64(salt, static_cast<unsigned char>(c));
    Rng rng(sim_detail::mix64(seed, salt));
    e.build(o, rng);
    o.validate();
    return o;
  }
  std::string known;
  for (const Entry& e : kScenarios) known += (known.empty() ? "" : ", ") + std::string(e.info.name);
  throw ConfigError("scenario", "one of " + known + " (not '" + std::string(name) + "')");
}

}  // namespace rgbl
