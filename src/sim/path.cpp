#include "rgbl/sim/path.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rgbl {
namespace {

// Open paths are laid out this far beyond the requested length, so that the street ahead of the last
// frame looks like the rest of it.
constexpr double kOpenMargin = 150.0;
// m between a loop's lane change (PathOptions::loop_lap_offset) and the start, and ahead of the change
constexpr double kLapChangeMargin = 10.0;

PathPoint advance(const PathPoint& p0, double curvature, double ds) {
  PathPoint p;
  if (curvature == 0.0) {
    p.heading = p0.heading;
    p.x = p0.x + ds * std::sin(p0.heading);
    p.z = p0.z + ds * std::cos(p0.heading);
    return p;
  }
  p.heading = p0.heading - curvature * ds;
  p.x = p0.x + (std::cos(p.heading) - std::cos(p0.heading)) / curvature;
  p.z = p0.z - (std::sin(p.heading) - std::sin(p0.heading)) / curvature;
  return p;
}

}  // namespace

std::string_view to_string(PathKind kind) {
  switch (kind) {
    case PathKind::straight: return "straight";
    case PathKind::curve: return "curve";
    case PathKind::loop: return "loop";
    case PathKind::turn: return "turn";
  }
  return "unknown";
}

std::optional<PathKind> parse_path_kind(std::string_view name) {
  if (name == "straight") return PathKind::straight;
  if (name == "curve") return PathKind::curve;
  if (name == "loop") return PathKind::loop;
  if (name == "turn") return PathKind::turn;
  return std::nullopt;
}

void PathOptions::validate() const {
  require(bend_radius >= 15.0, "path.bend_radius", "a radius of at least 15 m");
  require(bend_angle_deg > 0.0 && bend_angle_deg <= 180.0, "path.bend_angle_deg", "an angle in (0, 180] degrees");
  require(bend_straight >= 0.0, "path.bend_straight", "a length >= 0 m");
  require(loop_corner_radius >= 12.0, "path.loop_corner_radius", "a radius of at least 12 m");
  require(loop_laps >= 1 && loop_laps <= 100, "path.loop_laps", "1..100 laps");
  require(std::isfinite(loop_lap_offset) && std::abs(loop_lap_offset) <= 6.0, "path.loop_lap_offset",
          "an offset of at most 6 m either side");
  require(loop_lap_change >= 10.0 && loop_lap_change <= 200.0, "path.loop_lap_change", "10..200 m");
  require(std::isfinite(turn_start) && turn_start >= 0.0, "path.turn_start", "a length >= 0 m");
  require(turn_radius >= 8.0 && turn_radius <= 1000.0, "path.turn_radius", "a radius in [8, 1000] m");
  require(turn_angle_deg != 0.0 && std::abs(turn_angle_deg) <= 180.0, "path.turn_angle_deg",
          "a non-zero angle in [-180, 180] degrees");
}

SpeedProfile::SpeedProfile(double initial_speed, std::vector<SpeedPhase> phases, const char* key) {
  require(std::isfinite(initial_speed) && initial_speed >= 0.0, key, "an initial speed >= 0 m/s");
  double t = 0.0, v = initial_speed, d = 0.0;
  for (const SpeedPhase& p : phases) {
    require(std::isfinite(p.duration) && p.duration >= 0.0 && std::isfinite(p.acceleration), key,
            "phases of finite duration >= 0 s and finite acceleration");
    knots_.push_back({t, v, d, p.acceleration});
    double v_end = v + p.acceleration * p.duration;
    require(v_end > -1e-9, key, "phases that never make the speed negative");
    if (std::abs(v_end) < 1e-9) v_end = 0.0;  // stopped means standing exactly still
    d += 0.5 * (v + v_end) * p.duration;
    t += p.duration;
    v = v_end;
  }
  knots_.push_back({t, v, d, 0.0});
}

double SpeedProfile::speed(double t) const {
  auto it = std::upper_bound(knots_.begin(), knots_.end(), t, [](double x, const Knot& k) { return x < k.t; });
  const Knot& k = it == knots_.begin() ? knots_.front() : *std::prev(it);
  if (&k == &knots_.back()) return k.speed;
  return k.speed + k.acceleration * (t - k.t);
}

double SpeedProfile::distance(double t) const {
  auto it = std::upper_bound(knots_.begin(), knots_.end(), t, [](double x, const Knot& k) { return x < k.t; });
  const Knot& k = it == knots_.begin() ? knots_.front() : *std::prev(it);
  const double dt = t - k.t;
  if (&k == &knots_.back() || k.acceleration == 0.0) return k.distance + k.speed * dt;
  // a phase that brakes to 0 before its end is excluded by the constructor, so no clamping here
  return k.distance + k.speed * dt + 0.5 * k.acceleration * dt * dt;
}

Eigen::Vector2d PathPoint::forward() const { return {std::sin(heading), std::cos(heading)}; }
Eigen::Vector2d PathPoint::right() const { return {std::cos(heading), -std::sin(heading)}; }

DrivePath::DrivePath(const PathOptions& options, double length) {
  options.validate();
  require(std::isfinite(length) && length >= 0.0, "path.length", "a finite length >= 0 m");
  switch (options.kind) {
    case PathKind::straight:
      segments_.push_back({length + kOpenMargin, 0.0});
      break;
    case PathKind::curve: {
      const double arc = options.bend_radius * options.bend_angle_deg * std::numbers::pi / 180.0;
      double covered = 0.0;
      for (int bend = 0; covered < length + kOpenMargin; ++bend) {
        if (options.bend_straight > 0.0) segments_.push_back({options.bend_straight, 0.0});
        const double sign = bend % 2 == 0 ? 1.0 : -1.0;
        segments_.push_back({arc, sign / options.bend_radius});
        covered += options.bend_straight + arc;
      }
      break;
    }
    case PathKind::turn: {
      const double angle = std::abs(options.turn_angle_deg) * std::numbers::pi / 180.0;
      const double sign = options.turn_angle_deg > 0.0 ? 1.0 : -1.0;
      if (options.turn_start > 0.0) segments_.push_back({options.turn_start, 0.0});
      segments_.push_back({options.turn_radius * angle, sign / options.turn_radius});
      segments_.push_back({std::max(1.0, length + kOpenMargin - options.turn_start - options.turn_radius * angle), 0.0});
      break;
    }
    case PathKind::loop: {
      length /= options.loop_laps;  // the perimeter
      const double radius = options.loop_corner_radius;
      const double corners = 2.0 * std::numbers::pi * radius;
      require(length >= corners, "path.loop_corner_radius",
              "a corner radius whose full circle (2 pi r) fits into the loop's length");
      // Start and end halfway along a side, so that the car comes back to the start on a straight.
      const double side = (length - corners) / 4.0;
      if (side > 0.0) segments_.push_back({0.5 * side, 0.0});
      for (int i = 0; i < 4; ++i) {
        segments_.push_back({corners / 4.0, 1.0 / radius});
        if (side > 0.0) segments_.push_back({i < 3 ? side : 0.5 * side, 0.0});
      }
      closed_ = true;
      lap_offset_ = options.loop_lap_offset;
      lap_change_ = options.loop_lap_change;
      require(lap_offset_ == 0.0 || length >= lap_change_ + 2.0 * kLapChangeMargin, "path.loop_lap_change",
              "a lane change that fits into the first lap with 10 m to spare at either end");
      break;
    }
  }
  build_starts();
  // The loop's perimeter is the requested length itself (not the sum of its rounded pieces), so that
  // s = length maps exactly onto s = 0.
  if (closed_) total_length_ = length;
}

DrivePath::DrivePath(std::vector<PathSegment> segments, bool closed) : segments_(std::move(segments)), closed_(closed) {
  for (const auto& seg : segments_) {
    require(std::isfinite(seg.length) && seg.length > 0.0, "path.segments", "segments of positive finite length");
    require(std::isfinite(seg.curvature), "path.segments", "finite curvatures");
  }
  require(!segments_.empty(), "path.segments", "at least one segment");
  build_starts();
}

void DrivePath::build_starts() {
  starts_.clear();
  start_s_.clear();
  PathPoint p;
  double s = 0.0;
  for (const auto& seg : segments_) {
    starts_.push_back(p);
    start_s_.push_back(s);
    p = advance(p, seg.curvature, seg.length);
    s += seg.length;
  }
  starts_.push_back(p);  // the end state, used to extrapolate open paths
  start_s_.push_back(s);
  total_length_ = s;
}

PathPoint DrivePath::at(double s) const {
  if (closed_) {
    s = std::fmod(s, total_length_);
    if (s < 0.0) s += total_length_;
  }
  if (s < 0.0) return advance(starts_.front(), 0.0, s);
  if (s >= start_s_.back()) {
    if (closed_) return starts_.front();  // rounding of the pieces' sum: the loop's end is its start
    return advance(starts_.back(), 0.0, s - start_s_.back());
  }
  const auto it = std::upper_bound(start_s_.begin(), start_s_.end(), s);
  const auto i = static_cast<std::size_t>(std::distance(start_s_.begin(), it) - 1);
  return advance(starts_[i], segments_[i].curvature, s - start_s_[i]);
}

Eigen::Vector2d DrivePath::point(double s, double lateral) const {
  const PathPoint p = at(s);
  return Eigen::Vector2d(p.x, p.z) + lateral * p.right();
}

double DrivePath::camera_offset(double s) const {
  if (lap_offset_ == 0.0) return 0.0;
  // a smoothstep from the first lap's track to the offset, ending kLapChangeMargin before the start
  const double t = std::clamp((s - (total_length_ - kLapChangeMargin - lap_change_)) / lap_change_, 0.0, 1.0);
  return lap_offset_ * t * t * (3.0 - 2.0 * t);
}

Eigen::Isometry3d DrivePath::pose(double s) const {
  PathPoint p = at(s);
  constexpr double h = 0.005;
  const double offset = camera_offset(s), behind = camera_offset(s - h), ahead = camera_offset(s + h);
  if (offset != 0.0 || behind != 0.0 || ahead != 0.0) {
    const Eigen::Vector2d here = point(s, offset);
    if (behind != ahead) {
      // in the lane change: heading along the camera's own motion, by a central difference over 1 cm
      // (the change turns the car by at most atan(1.5 offset / change), 9 deg for 3.3 m over 30 m)
      const Eigen::Vector2d step = point(s + h, ahead) - point(s - h, behind);
      p.heading = std::atan2(step.x(), step.y());
    }
    p.x = here.x();
    p.z = here.y();
  }
  const double c = std::cos(p.heading), sn = std::sin(p.heading);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << c, 0.0, sn, 0.0, 1.0, 0.0, -sn, 0.0, c;
  T.translation() << p.x, 0.0, p.z;
  return T;
}

}  // namespace rgbl
