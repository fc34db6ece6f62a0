#pragma once
// The vehicle's path through the synthetic street: a chain of straight segments and circular arcs on
// the flat road, driven at constant speed with the camera level.
//
// World frame = rectified cam0 of the first frame (KITTI convention): x right, y down, z forward. The
// road is the plane y = camera height. A heading psi points the camera along (sin psi, 0, cos psi);
// left turns decrease psi.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>
#include <string_view>
#include <vector>

namespace rgbl {

enum class PathKind {
  straight,  // one straight street
  curve,     // straights joined by bends, alternately left and right
  loop,      // a rounded square of left turns, from halfway along a side back to exactly the start
  turn,      // a straight, one bend (a junction's 90 degree turn), then straight on
};

std::string_view to_string(PathKind kind);
// "straight", "curve", "loop" or "turn"; nullopt for anything else.
std::optional<PathKind> parse_path_kind(std::string_view name);

struct PathOptions {
  PathKind kind = PathKind::straight;
  double bend_radius = 40.0;        // m, radius of the bends of "curve" (of the camera's track)
  double bend_angle_deg = 60.0;     // turn of each bend of "curve"
  double bend_straight = 30.0;      // m of straight before each bend of "curve"
  double loop_corner_radius = 15.0; // m, radius of the four corners of "loop"
  int loop_laps = 1;                // laps of "loop" in the driven length (2: the start is passed once)
  // The later laps of "loop" a lane to the side: metres right (+) or left (-) of the first lap's
  // track, reached by a lane change over `loop_lap_change` m that ends 10 m before the start. 0: every
  // lap on the same track (the viewpoints repeat to within a frame's step).
  double loop_lap_offset = 0.0;
  double loop_lap_change = 30.0;
  double turn_start = 20.0;         // m of straight before the bend of "turn"
  double turn_radius = 12.0;        // m, radius of the bend of "turn" (of the camera's track)
  double turn_angle_deg = 90.0;     // > 0 turns left, < 0 right

  void validate() const;
};

// One piece of the path: a straight (curvature 0) or a circular arc (curvature 1/radius, > 0 turns left).
struct PathSegment {
  double length = 0.0;     // m
  double curvature = 0.0;  // 1/m
};

// Position and heading at one arc length.
struct PathPoint {
  double x = 0.0, z = 0.0;  // world position on the camera's track
  double heading = 0.0;     // psi, radians

  Eigen::Vector2d forward() const;  // (x, z) of the driving direction
  Eigen::Vector2d right() const;    // (x, z) of the camera's +x axis
};

// Speed over time as phases of constant acceleration after an initial speed; after the last phase the
// speed stays. A vehicle that brakes to 0 stands exactly still (its distance does not change by a bit).
struct SpeedPhase {
  double duration = 0.0;      // s
  double acceleration = 0.0;  // m/s^2, < 0 brakes
};

class SpeedProfile {
 public:
  // Throws ConfigError naming `key` when the speed would become negative or a phase is not finite.
  explicit SpeedProfile(double initial_speed = 10.0, std::vector<SpeedPhase> phases = {},
                        const char* key = "speed_phases");

  double speed(double t) const;     // m/s at time t >= 0
  double distance(double t) const;  // m driven in [0, t]

 private:
  struct Knot {
    double t, speed, distance;  // at the start of a phase
    double acceleration;
  };
  std::vector<Knot> knots_;  // the last one holds the final speed with zero acceleration
};

class DrivePath {
 public:
  // The path of the given kind that covers `length` metres from the start. An open path (straight,
  // curve) continues beyond `length` in the same pattern, and straight before 0 and after its last
  // segment, so that a scene can be laid out around it. A loop's perimeter is exactly `length` divided
  // by its laps.
  DrivePath(const PathOptions& options, double length);
  // A custom chain of segments starting at the origin with heading 0; `closed` makes s wrap around.
  DrivePath(std::vector<PathSegment> segments, bool closed);

  // Arc length covered by the segments (a loop's perimeter).
  double length() const { return total_length_; }
  bool closed() const { return closed_; }
  const std::vector<PathSegment>& segments() const { return segments_; }

  PathPoint at(double s) const;
  // Point at lateral offset `lateral` (metres, + = right of the driving direction) from the track.
  Eigen::Vector2d point(double s, double lateral) const;
  // T_world_cam0 of a level camera on the track at arc length s (camera at y = 0), s counted from the
  // start over all laps: on a loop with a lap offset the camera leaves the track (PathOptions), its
  // heading along its own motion.
  Eigen::Isometry3d pose(double s) const;
  // The camera's lateral offset from the track at arc length s (0 without a lap offset).
  double camera_offset(double s) const;

 private:
  void build_starts();

  std::vector<PathSegment> segments_;
  std::vector<PathPoint> starts_;    // state at the start of each segment
  std::vector<double> start_s_;      // arc length at the start of each segment
  double total_length_ = 0.0;
  bool closed_ = false;
  double lap_offset_ = 0.0, lap_change_ = 30.0;
};

}  // namespace rgbl
