#include "rgbl/sim/synthetic.hpp"

#include "hash.hpp"
#include "rgbl/core/error.hpp"
#include "texture.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <thread>

namespace rgbl {
namespace {

using sim_detail::Rgb;

constexpr double kKittiWidth = 1226.0, kKittiHeight = 370.0;
constexpr double kDeg = std::numbers::pi / 180.0;
using sim_detail::kInf;

// Runs fn(i) for i in [0, n), items interleaved over `threads` threads (rows of an image differ in
// cost: sky is cheap, street is not). Results must not depend on which thread ran an item.
template <typename Fn>
void parallel_for(int n, int threads, Fn&& fn) {
  threads = std::clamp(threads, 1, std::max(1, n));
  if (threads == 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::vector<std::jthread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) {
    pool.emplace_back([&, t] {
      for (int i = t; i < n; i += threads) fn(i);
    });
  }
  for (int i = 0; i < n; i += threads) fn(i);
}

// An approximately normal deviate (Irwin-Hall of four uniforms, variance 1) from one hash: cheap
// enough for per-pixel image noise.
float pixel_noise(std::uint64_t h) {
  float sum = 0.0F;
  for (int i = 0; i < 4; ++i) sum += static_cast<float>((h >> (16 * i)) & 0xFFFFU) * (1.0F / 65536.0F);
  return (sum - 2.0F) * 1.7320508F;
}

// The street at one instant: the static scene plus the actors' boxes at that time. Actor ids follow
// the static objects' ids.
class FrameScene {
 public:
  FrameScene(const StreetScene& scene, std::vector<SceneObject> actors)
      : scene_(scene), actors_(std::move(actors)), static_count_(static_cast<std::uint32_t>(scene.objects().size())) {
    for (const SceneObject& a : actors_) {
      bounds_.push_back({{a.cx, a.cy, a.cz}, std::sqrt(a.hx * a.hx + a.hy * a.hy + a.hz * a.hz)});
    }
  }

  const StreetScene& street() const { return scene_; }
  const std::vector<SceneObject>& actors() const { return actors_; }
  std::uint32_t static_count() const { return static_count_; }
  bool is_actor(std::uint32_t id) const { return id != StreetScene::kGround && id >= static_count_; }
  const SceneObject& object(std::uint32_t id) const {
    return id < static_count_ ? scene_.objects()[id] : actors_[id - static_count_];
  }

  std::optional<RayHit> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& d, double t_max,
                                  double t_min = 1e-6) const {
    std::optional<RayHit> hit = scene_.intersect(origin, d, t_max, t_min);
    double best = hit ? hit->t : t_max;
    std::uint8_t face = 0;
    const double dd = d.squaredNorm();
    for (std::size_t k = 0; k < actors_.size(); ++k) {
      // a cheap test against the box's bounding sphere first: most rays pass far from most vehicles
      const Eigen::Vector3d oc = bounds_[k].centre - origin;
      const double along = oc.dot(d) / dd, r2 = bounds_[k].radius * bounds_[k].radius;
      if ((along < 0.0 && oc.squaredNorm() > r2) || (oc - along * d).squaredNorm() > r2) continue;
      if (along - bounds_[k].radius / std::sqrt(dd) >= best) continue;  // beyond what was hit already
      if (intersect_object(actors_[k], origin, d, t_min, best, face)) {
        hit = RayHit{best, static_count_ + static_cast<std::uint32_t>(k), face};
      }
    }
    return hit;
  }

  SurfacePoint surface(const RayHit& hit, const Eigen::Vector3d& origin, const Eigen::Vector3d& d) const {
    if (!is_actor(hit.object)) return scene_.surface(hit, origin, d);
    return object_surface(object(hit.object), scene_.ground_y(), hit.face, origin + hit.t * d);
  }

 private:
  struct Sphere {
    Eigen::Vector3d centre;
    double radius;
  };
  const StreetScene& scene_;
  std::vector<SceneObject> actors_;
  std::vector<Sphere> bounds_;
  std::uint32_t static_count_;
};

// Casts the rays of one camera at one pose. Objects are binned into 8x8-pixel tiles by their
// projected bounds, nearest first; camera rays are (x, y, 1) in the camera frame, so the ray
// parameter is the depth and a ray can stop at the first object whose nearest corner is farther
// than its current hit. Much cheaper than the scene's general grid walk for a whole image.
class ViewCaster {
 public:
  static constexpr int kTile = 8;

  ViewCaster(const FrameScene& scene, const Eigen::Isometry3d& T_world_cam, const PinholeCamera& cam)
      : scene_(scene), cam_(cam), R_(T_world_cam.linear()), origin_(T_world_cam.translation()) {
    const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
    tiles_x_ = (cam.width + kTile - 1) / kTile;
    tiles_y_ = (cam.height + kTile - 1) / kTile;
    struct Span {
      std::uint32_t id;
      double z_min;
      int tx0, tx1, ty0, ty1;
    };
    std::vector<Span> spans;
    constexpr double kNear = 0.01;
    const std::size_t n_objects = scene.static_count() + scene.actors().size();
    for (std::size_t i = 0; i < n_objects; ++i) {
      const SceneObject& o = scene.object(static_cast<std::uint32_t>(i));
      const double ax = o.shape == SceneObject::Shape::box ? o.ax : 1.0;  // round shapes: their bounding box
      const double az = o.shape == SceneObject::Shape::box ? o.az : 0.0;
      std::array<Eigen::Vector3d, 8> c;
      for (int k = 0; k < 8; ++k) {
        const double sx = (k & 1) != 0 ? o.hx : -o.hx, sy = (k & 2) != 0 ? o.hy : -o.hy, sz = (k & 4) != 0 ? o.hz : -o.hz;
        const Eigen::Vector3d w(o.cx + sx * ax - sz * az, o.cy + sy, o.cz + sx * az + sz * ax);
        c[static_cast<std::size_t>(k)] = T_cam_world * w;
      }
      double z_min = kInf, z_max = -kInf;
      for (const auto& p : c) {
        z_min = std::min(z_min, p.z());
        z_max = std::max(z_max, p.z());
      }
      if (z_max <= kNear) continue;  // wholly behind the camera
      // Bounds of the box's part in front of the near plane: its corners there and where its edges
      // cross the plane.
      double u0 = kInf, u1 = -kInf, v0 = kInf, v1 = -kInf;
      auto add = [&](const Eigen::Vector3d& p) {
        const double u = cam.fx * p.x() / p.z() + cam.cx, v = cam.fy * p.y() / p.z() + cam.cy;
        u0 = std::min(u0, u);
        u1 = std::max(u1, u);
        v0 = std::min(v0, v);
        v1 = std::max(v1, v);
      };
      for (int a = 0; a < 8; ++a) {
        const auto& pa = c[static_cast<std::size_t>(a)];
        if (pa.z() > kNear) add(pa);
        for (const int bit : {1, 2, 4}) {  // the three edges from corner a to a corner with a higher index
          if ((a & bit) != 0) continue;
          const auto& pb = c[static_cast<std::size_t>(a | bit)];
          if ((pa.z() > kNear) != (pb.z() > kNear)) add(pa + (kNear - pa.z()) / (pb.z() - pa.z()) * (pb - pa));
        }
      }
      // Samples lie within half a pixel of their pixel's centre.
      const int tx0 = std::max(0, static_cast<int>(std::floor((u0 - 0.6) / kTile)));
      const int tx1 = std::min(tiles_x_ - 1, static_cast<int>(std::floor(std::min(u1 + 0.6, 1e6) / kTile)));
      const int ty0 = std::max(0, static_cast<int>(std::floor((v0 - 0.6) / kTile)));
      const int ty1 = std::min(tiles_y_ - 1, static_cast<int>(std::floor(std::min(v1 + 0.6, 1e6) / kTile)));
      if (tx0 > tx1 || ty0 > ty1) continue;
      spans.push_back({static_cast<std::uint32_t>(i), std::max(z_min, 0.0), tx0, tx1, ty0, ty1});
    }
    std::stable_sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) { return a.z_min < b.z_min; });
    const auto n_tiles = static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_);
    start_.assign(n_tiles + 1, 0);
    for (const auto& sp : spans)
      for (int ty = sp.ty0; ty <= sp.ty1; ++ty)
        for (int tx = sp.tx0; tx <= sp.tx1; ++tx) ++start_[static_cast<std::size_t>(ty * tiles_x_ + tx) + 1];
    for (std::size_t t = 0; t < n_tiles; ++t) start_[t + 1] += start_[t];
    entries_.resize(start_[n_tiles]);
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (const auto& sp : spans)
      for (int ty = sp.ty0; ty <= sp.ty1; ++ty)
        for (int tx = sp.tx0; tx <= sp.tx1; ++tx) entries_[fill[static_cast<std::size_t>(ty * tiles_x_ + tx)]++] = {sp.id, sp.z_min};
  }

  const Eigen::Vector3d& origin() const { return origin_; }

  // World direction of the ray through image point (x, y) (pixel units, integer at pixel centres).
  Eigen::Vector3d direction(double x, double y) const {
    return R_ * Eigen::Vector3d((x - cam_.cx) / cam_.fx, (y - cam_.cy) / cam_.fy, 1.0);
  }

  // First hit of direction d, cast from within pixel (u, v); t is the camera depth.
  std::optional<RayHit> cast(int u, int v, const Eigen::Vector3d& d) const {
    double best = kInf;
    bool ground = false;
    if (d.y() > 0.0) {
      best = (scene_.street().ground_y() - origin_.y()) / d.y();
      ground = true;
    }
    std::uint32_t hit = StreetScene::kGround;
    std::uint8_t face = 0;
    const auto tile = static_cast<std::size_t>((v / kTile) * tiles_x_ + u / kTile);
    for (std::uint32_t k = start_[tile]; k < start_[tile + 1]; ++k) {
      const Entry& e = entries_[k];
      if (e.z_min >= best) break;
      if (intersect_object(scene_.object(e.id), origin_, d, 1e-9, best, face)) hit = e.id;
    }
    if (hit != StreetScene::kGround) return RayHit{best, hit, face};
    if (ground) return RayHit{best, StreetScene::kGround, 0};
    return std::nullopt;
  }

 private:
  struct Entry {
    std::uint32_t id;
    double z_min;
  };
  const FrameScene& scene_;
  PinholeCamera cam_;
  Eigen::Matrix3d R_;
  Eigen::Vector3d origin_;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<std::uint32_t> start_;
  std::vector<Entry> entries_;
};

Rgb sky(const Eigen::Vector3d& d) {
  const double up = std::clamp(-d.y() / d.norm() * 2.5, 0.0, 1.0);
  const auto w = static_cast<float>(up);
  return {0.86F + (0.45F - 0.86F) * w, 0.89F + (0.60F - 0.89F) * w, 0.93F + (0.86F - 0.93F) * w};
}

// Share of the sunlight that reaches point p (normal n): 0 behind a wall, an actor or a hedge, 1 in the
// open; a tree's crown lets it through where its leaves have gaps.
double sunlight(const FrameScene& scene, const LightOptions& light, const Eigen::Vector3d& sun, const Eigen::Vector3d& p,
                const Eigen::Vector3d& n) {
  Eigen::Vector3d origin = p + 1e-4 * n;
  for (int pass = 0; pass < 4; ++pass) {
    const auto hit = scene.intersect(origin, sun, 300.0, 1e-6);
    if (!hit) return 1.0;
    const SceneObject& o = scene.object(hit->object);
    const Eigen::Vector3d q = origin + hit->t * sun;
    if (hit->object == StreetScene::kGround || o.shape != SceneObject::Shape::sphere ||
        !sim_detail::leaf_gap(q, light.leaf_gap)) {
      return 0.0;
    }
    // through a gap: on from just inside the crown (a ray from inside a sphere does not hit it again)
    origin = q + 1e-4 * sun;
  }
  return 0.0;
}

// Radiance of a hit: albedo under the sun plus ambient light (Lambertian; the view does not enter),
// or the sky when nothing was hit.
Rgb shade(const FrameScene& scene, const LightOptions& light, const Eigen::Vector3d& sun,
          const std::optional<RayHit>& hit, const Eigen::Vector3d& origin, const Eigen::Vector3d& d, double pixel_angle,
          bool blank) {
  if (!hit) return sky(d);
  SurfacePoint s = scene.surface(*hit, origin, d);
  if (blank && s.kind == SurfaceKind::marking) s.kind = SurfaceKind::road;  // plain road, no paint
  const double len = d.norm();
  const double cos_incidence = std::max(std::abs(s.normal.dot(d)) / len, 0.05);
  // Four samples per pixel: each stands for half a pixel. A slanted surface stretches the footprint
  // along one axis only: take the geometric mean of its two axes.
  const double footprint = blank ? kInf : 0.5 * hit->t * len * pixel_angle / std::sqrt(cos_incidence);
  const Rgb a = sim_detail::albedo(s, footprint);
  double direct = std::max(0.0, s.normal.dot(sun));
  if (light.cast_shadows && direct > 0.0) direct *= sunlight(scene, light, sun, origin + hit->t * d, s.normal);
  const auto k = static_cast<float>(light.ambient + light.sun * direct);
  return {a.r * k, a.g * k, a.b * k};
}

// Each pixel averages the sharp image along its own motion during the exposure (a gather along the
// pixel's flow, centred on the pixel; bilinear samples, clamped at the border).
cv::Mat_<cv::Vec3f> motion_blur(const cv::Mat_<cv::Vec3f>& sharp, const cv::Mat_<cv::Vec2f>& flow, int threads) {
  cv::Mat_<cv::Vec3f> out(sharp.rows, sharp.cols);
  const int w = sharp.cols, h = sharp.rows;
  auto sample = [&](double x, double y) {
    x = std::clamp(x, 0.0, w - 1.0);
    y = std::clamp(y, 0.0, h - 1.0);
    // images are at least 32x16 pixels (validate()), so x0 + 1 and y0 + 1 stay inside
    const int x0 = std::min(static_cast<int>(x), w - 2), y0 = std::min(static_cast<int>(y), h - 2);
    const auto fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
    const int x1 = x0 + 1, y1 = y0 + 1;
    return (sharp(y0, x0) * (1.0F - fx) + sharp(y0, x1) * fx) * (1.0F - fy) +
           (sharp(y1, x0) * (1.0F - fx) + sharp(y1, x1) * fx) * fy;
  };
  parallel_for(h, threads, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const cv::Vec2f f = flow(v, u);
      const double len = std::hypot(f[0], f[1]);
      if (len < 0.25) {
        out(v, u) = sharp(v, u);
        continue;
      }
      const int n = std::min(48, static_cast<int>(std::ceil(len)) + 1);
      cv::Vec3f sum(0.0F, 0.0F, 0.0F);
      for (int k = 0; k <= n; ++k) {
        const double a = static_cast<double>(k) / n - 0.5;
        sum += sample(u + a * f[0], v + a * f[1]);
      }
      out(v, u) = sum * (1.0F / static_cast<float>(n + 1));
    }
  });
  return out;
}

std::uint8_t to_byte(float value) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
}

}  // namespace

KittiCalibration kitti_odometry_04_calibration() {
  KittiCalibration c;
  c.P[0] << 7.070912e+02, 0.0, 6.018873e+02, 0.0, 0.0, 7.070912e+02, 1.831104e+02, 0.0, 0.0, 0.0, 1.0, 0.0;
  c.P[1] << 7.070912e+02, 0.0, 6.018873e+02, -3.798145e+02, 0.0, 7.070912e+02, 1.831104e+02, 0.0, 0.0, 0.0, 1.0, 0.0;
  c.P[2] << 7.070912e+02, 0.0, 6.018873e+02, 4.688783e+01, 0.0, 7.070912e+02, 1.831104e+02, 1.178601e-01, 0.0, 0.0,
      1.0, 6.203223e-03;
  c.P[3] << 7.070912e+02, 0.0, 6.018873e+02, -3.334597e+02, 0.0, 7.070912e+02, 1.831104e+02, 1.930130e+00, 0.0, 0.0,
      1.0, 3.318498e-03;
  Matrix34d Tr;
  Tr << -1.857739385241e-03, -9.999659513510e-01, -8.039975204516e-03, -4.784029760483e-03, -6.481465826011e-03,
      8.051860151134e-03, -9.999466081774e-01, -7.337429464231e-02, 9.999773098287e-01, -1.805528627661e-03,
      -6.496203536139e-03, -3.339968064433e-01;
  // KITTI's rotation is orthonormal to ~1e-7 only; re-orthonormalise so that Tr is an exact rigid motion.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(Tr.leftCols<3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  c.T_cam0_lidar = make_isometry(svd.matrixU() * svd.matrixV().transpose(), Tr.col(3));
  c.width.fill(static_cast<int>(kKittiWidth));
  c.height.fill(static_cast<int>(kKittiHeight));
  return c;
}

void SimLidarOptions::validate() const {
  require(beams >= 2 && beams <= 256, "lidar.beams", "2..256 beams");
  require(max_elevation_deg < 60.0 && min_elevation_deg > -60.0 && max_elevation_deg > min_elevation_deg,
          "lidar.max_elevation_deg", "-60 < lidar.min_elevation_deg < lidar.max_elevation_deg < 60");
  require(azimuth_step_deg >= 0.01 && azimuth_step_deg <= 10.0, "lidar.azimuth_step_deg", "a step in [0.01, 10] degrees");
  require(min_range >= 0.0 && max_range > min_range, "lidar.max_range", "0 <= lidar.min_range < lidar.max_range");
  require(range_noise_sigma >= 0.0 && range_noise_sigma < 1.0, "lidar.range_noise_sigma", "a sigma in [0, 1) m");
  require(dropout >= 0.0 && dropout < 1.0, "lidar.dropout", "a probability in [0, 1)");
  require(foliage_penetration >= 0.0 && foliage_penetration <= 2.0, "lidar.foliage_penetration",
          "a mean depth in [0, 2] m");
  require(std::isfinite(elevation_offset_deg) && std::abs(elevation_offset_deg) <= 2.0, "lidar.elevation_offset_deg",
          "an offset in [-2, 2] deg");
  require(std::isfinite(beam_elevation_sigma_deg) && beam_elevation_sigma_deg >= 0.0 && beam_elevation_sigma_deg <= 2.0,
          "lidar.beam_elevation_sigma_deg", "a sigma in [0, 2] deg");
  require(T_cam0_lidar.matrix().allFinite(), "lidar.T_cam0_lidar", "a finite rigid transform");
}

std::vector<double> SimLidarOptions::elevations_deg() const {
  // HDL-64E: the upper block's 32 lasers are 1/3 deg apart over the top 10.33 deg of the 26.8 deg
  // field, the lower block's 32 spread over the rest after a half-degree gap.
  const int upper = beams / 2, lower = beams - upper;
  const double span = max_elevation_deg - min_elevation_deg;
  const double upper_span = span * (31.0 / 3.0) / 26.8;
  const double upper_step = upper > 1 ? upper_span / (upper - 1) : 0.0;
  const double lower_top = max_elevation_deg - upper_span - 1.5 * upper_step;
  std::vector<double> e;
  for (int i = 0; i < upper; ++i) e.push_back(max_elevation_deg - i * upper_step);
  for (int i = 0; i < lower; ++i) {
    e.push_back(lower > 1 ? lower_top - i * (lower_top - min_elevation_deg) / (lower - 1) : min_elevation_deg);
  }
  return e;
}

void LightOptions::validate() const {
  require(sun_direction.allFinite() && sun_direction.norm() > 1e-6, "light.sun_direction", "a finite non-zero vector");
  require(ambient >= 0.0 && ambient <= 4.0, "light.ambient", "a level in [0, 4]");
  require(sun >= 0.0 && sun <= 4.0, "light.sun", "a level in [0, 4]");
  require(leaf_gap >= 0.0 && leaf_gap <= 1.0, "light.leaf_gap", "a share in [0, 1]");
}

void SyntheticOptions::validate() const {
  require(frames >= 1 && frames <= 100000, "frames", "1..100000 frames");
  require(std::isfinite(speed) && speed > 0.0 && speed <= 60.0, "speed", "a speed in (0, 60] m/s");
  require(std::isfinite(frame_period) && frame_period > 0.0 && frame_period <= 10.0, "frame_period",
          "a period in (0, 10] s");
  require(width >= 32 && width <= 4096, "width", "32..4096 pixels");
  require(height >= 16 && height <= 4096, "height", "16..4096 pixels");
  require(image_noise_sigma >= 0.0 && image_noise_sigma <= 50.0, "image_noise_sigma", "a sigma in [0, 50] grey levels");
  require(depth_camera >= 0 && depth_camera <= 3, "depth_camera", "a camera index 0..3");
  require(threads >= 1 && threads <= 64, "threads", "1..64 threads");
  path.validate();
  scene.validate();
  lidar.validate();
  light.validate();
  (void)speed_profile();  // throws naming speed_phases
  for (const Actor& a : actors) a.validate("actors");
  for (const ExposureStep& e : exposure_steps) {
    require(e.frame >= 0 && std::isfinite(e.gain) && e.gain > 0.05 && e.gain < 20.0, "exposure_steps",
            "steps at frames >= 0 with a gain in (0.05, 20)");
  }
  require(exposure_drift >= 0.0 && exposure_drift < 1.0, "exposure_drift", "a relative amplitude in [0, 1)");
  require(exposure_drift_period >= 2.0, "exposure_drift_period", "at least 2 frames");
  require(exposure_time >= 0.0 && exposure_time <= 0.1, "exposure_time", "an exposure in [0, 0.1] s");
  require(lens_blur_sigma >= 0.0 && lens_blur_sigma <= 5.0, "lens_blur_sigma", "a sigma in [0, 5] pixels");
  require(contrast > 0.1 && contrast <= 4.0, "contrast", "a factor in (0.1, 4]");
  require(contrast_pivot >= 0.0 && contrast_pivot <= 255.0, "contrast_pivot", "a grey level in [0, 255]");
  if (path.kind == PathKind::loop) {
    require(driven_length() / path.loop_laps >= 2.0 * std::numbers::pi * path.loop_corner_radius, "frames",
            "enough frames for the loop: (frames - 1) * speed * frame_period >= path.loop_laps * 2 pi "
            "path.loop_corner_radius");
    require(std::abs(scene.lane_offset + path.loop_lap_offset) <= scene.road_half_width - scene.parking_width - 1.0,
            "path.loop_lap_offset", "an offset that keeps the camera 1 m inside the driving lanes");
  }
  if (untextured) {
    require(untextured->first >= 0 && untextured->first <= untextured->last && untextured->last < frames, "untextured",
            "a frame range first..last inside the sequence");
  }
  for (const int f : dropped_scans) require(f >= 0 && f < frames, "dropped_scans", "frame indices inside the sequence");
}

SyntheticGenerator::SyntheticGenerator(SyntheticOptions options) : options_(std::move(options)) {
  options_.validate();
  const double length = options_.driven_length();
  path_ = std::make_unique<DrivePath>(options_.path, length);
  scene_ = std::make_unique<StreetScene>(*path_, options_.scene, sim_detail::mix64(options_.seed, 0x5CE4EULL), -40.0,
                                         length + 120.0);

  // KITTI 04's rig scaled to the image size: same offsets between the cameras, scaled intrinsics.
  const KittiCalibration kitti = kitti_odometry_04_calibration();
  const double sx = options_.width / kKittiWidth, sy = options_.height / kKittiHeight;
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Matrix3d K04 = kitti.P[i].leftCols<3>();
    const Eigen::Vector3d t = K04.inverse() * kitti.P[i].col(3);
    Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
    K(0, 0) = K(1, 1) = K04(0, 0) * sx;
    K(0, 2) = (K04(0, 2) + 0.5) * sx - 0.5;  // pixel centres at integers
    K(1, 2) = (K04(1, 2) + 0.5) * sy - 0.5;
    calibration_.P[i].leftCols<3>() = K;
    calibration_.P[i].col(3) = K * t;
  }
  calibration_.T_cam0_lidar = options_.lidar.T_cam0_lidar;
  calibration_.width.fill(options_.width);
  calibration_.height.fill(options_.height);
}

double SyntheticGenerator::timestamp(int frame) const { return frame * options_.frame_period; }

double SyntheticGenerator::arc_length(int frame) const { return options_.speed_profile().distance(timestamp(frame)); }

Eigen::Isometry3d SyntheticGenerator::pose(int frame) const { return path_->pose(arc_length(frame)); }

Eigen::Isometry3d SyntheticGenerator::pose_at(double t) const {
  return path_->pose(options_.speed_profile().distance(t));
}

double SyntheticGenerator::exposure_gain(int frame) const {
  double gain = 1.0;
  for (const ExposureStep& e : options_.exposure_steps) {
    if (frame >= e.frame) gain *= e.gain;
  }
  if (options_.exposure_drift > 0.0) {
    gain *= 1.0 + options_.exposure_drift * std::sin(2.0 * std::numbers::pi * frame / options_.exposure_drift_period);
  }
  return gain;
}

std::vector<SceneObject> SyntheticGenerator::actor_boxes(int frame) const {
  return rgbl::actor_boxes(options_.actors, *path_, scene_->ground_y(), timestamp(frame));
}

std::optional<RayHit> SyntheticGenerator::intersect(int frame, const Eigen::Vector3d& origin,
                                                    const Eigen::Vector3d& direction, double t_max) const {
  const FrameScene scene(*scene_, actor_boxes(frame));
  return scene.intersect(origin, direction, t_max);
}

Eigen::Isometry3d SyntheticGenerator::T_world_camera(int frame, int camera) const {
  return pose(frame) * calibration_.camera(camera).T_cam_cam0.inverse();
}

cv::Mat_<cv::Vec2f> SyntheticGenerator::exposure_flow(int frame, int camera) const {
  const CameraCalibration cal = calibration_.camera(camera);
  const PinholeCamera& cam = cal.camera;
  const Eigen::Isometry3d T_cam0_cam = cal.T_cam_cam0.inverse();
  const double t = timestamp(frame), half = 0.5 * options_.exposure_time;
  const FrameScene scene(*scene_, actor_boxes(frame));
  const ViewCaster caster(scene, T_world_camera(frame, camera), cam);
  const std::vector<SceneObject> before = rgbl::actor_boxes(options_.actors, *path_, scene_->ground_y(), t - half);
  const std::vector<SceneObject> after = rgbl::actor_boxes(options_.actors, *path_, scene_->ground_y(), t + half);
  const Eigen::Isometry3d cam_before = (pose_at(t - half) * T_cam0_cam).inverse();
  const Eigen::Isometry3d cam_after = (pose_at(t + half) * T_cam0_cam).inverse();
  // a point carried by an actor's box from the frame's time to another: through the box's own frame
  auto carry = [](const SceneObject& from, const SceneObject& to, const Eigen::Vector3d& x) {
    const double rx = x.x() - from.cx, rz = x.z() - from.cz;
    const double lx = rx * from.ax + rz * from.az, lz = -rx * from.az + rz * from.ax, ly = x.y() - from.cy;
    return Eigen::Vector3d(to.cx + lx * to.ax - lz * to.az, to.cy + ly, to.cz + lx * to.az + lz * to.ax);
  };
  auto project = [&cam](const Eigen::Vector3d& p, Eigen::Vector2d& uv) {
    if (p.z() < 0.05) return false;
    uv = Eigen::Vector2d(cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy);
    return true;
  };
  cv::Mat_<cv::Vec2f> flow(cam.height, cam.width, cv::Vec2f(0.0F, 0.0F));
  parallel_for(cam.height, options_.threads, [&](int v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = caster.direction(u, v);
      const auto hit = caster.cast(u, v, d);
      // the sky moves with the camera's rotation only: a far point stands for it
      const Eigen::Vector3d x = caster.origin() + (hit ? hit->t : 1e4) * d;
      Eigen::Vector3d x0 = x, x1 = x;
      if (hit && scene.is_actor(hit->object)) {
        const std::size_t k = hit->object - scene.static_count();
        x0 = carry(scene.actors()[k], before[k], x);
        x1 = carry(scene.actors()[k], after[k], x);
      }
      Eigen::Vector2d a, b;
      if (project(cam_before * x0, a) && project(cam_after * x1, b)) {
        flow(v, u) = cv::Vec2f(static_cast<float>(b.x() - a.x()), static_cast<float>(b.y() - a.y()));
      }
    }
  });
  return flow;
}

cv::Mat_<float> SyntheticGenerator::blur_extent(int frame, int camera) const {
  require(frame >= 0 && frame < options_.frames, "frame", "a frame index inside the sequence");
  const cv::Mat_<cv::Vec2f> flow = exposure_flow(frame, camera);
  cv::Mat_<float> extent(flow.rows, flow.cols);
  for (int v = 0; v < flow.rows; ++v)
    for (int u = 0; u < flow.cols; ++u) extent(v, u) = std::hypot(flow(v, u)[0], flow(v, u)[1]);
  return extent;
}

cv::Mat SyntheticGenerator::render_image(int frame, int camera) const {
  require(frame >= 0 && frame < options_.frames, "frame", "a frame index inside the sequence");
  const CameraCalibration cal = calibration_.camera(camera);
  const PinholeCamera& cam = cal.camera;
  const FrameScene scene(*scene_, actor_boxes(frame));
  const ViewCaster caster(scene, T_world_camera(frame, camera), cam);
  const bool colour = camera >= 2;
  const bool blank = options_.untextured && options_.untextured->contains(frame);
  const auto sigma = static_cast<float>(options_.image_noise_sigma);
  const std::uint64_t noise_key = sim_detail::mix64(options_.seed, static_cast<std::uint64_t>(frame),
                                                    0x1A6E0000ULL + static_cast<std::uint64_t>(camera));
  const double pixel_angle = 1.0 / cam.fx;
  const Eigen::Vector3d sun = options_.light.sun_direction.normalized();
  // radiance summed over the pixel's four samples, before the camera's gain, blur and noise
  cv::Mat_<cv::Vec3f> radiance(cam.height, cam.width);
  constexpr double kOffsets[4][2] = {{-0.25, -0.25}, {0.25, -0.25}, {-0.25, 0.25}, {0.25, 0.25}};
  parallel_for(cam.height, options_.threads, [&](int v) {
    for (int u = 0; u < cam.width; ++u) {
      Rgb sum;
      for (const auto& o : kOffsets) {
        const Eigen::Vector3d d = caster.direction(u + o[0], v + o[1]);
        const Rgb c = shade(scene, options_.light, sun, caster.cast(u, v, d), caster.origin(), d, pixel_angle, blank);
        sum = {sum.r + c.r, sum.g + c.g, sum.b + c.b};
      }
      radiance(v, u) = cv::Vec3f(sum.r, sum.g, sum.b);
    }
  });
  if (options_.exposure_time > 0.0) radiance = motion_blur(radiance, exposure_flow(frame, camera), options_.threads);
  if (options_.lens_blur_sigma > 0.0) {
    cv::GaussianBlur(radiance, radiance, cv::Size(0, 0), options_.lens_blur_sigma, options_.lens_blur_sigma,
                     cv::BORDER_REPLICATE);
  }
  const auto gain = static_cast<float>(exposure_gain(frame));
  const auto contrast = static_cast<float>(options_.contrast), pivot = static_cast<float>(options_.contrast_pivot);
  // the tone curve, in grey levels; the identity (bit for bit) at contrast 1
  auto tone = [contrast, pivot](float level) { return contrast == 1.0F ? level : pivot + contrast * (level - pivot); };
  cv::Mat image(cam.height, cam.width, colour ? CV_8UC3 : CV_8UC1);
  parallel_for(cam.height, options_.threads, [&](int v) {
    auto* row = image.ptr<std::uint8_t>(v);
    for (int u = 0; u < cam.width; ++u) {
      cv::Vec3f sum = radiance(v, u);
      if (gain != 1.0F) sum *= gain;
      const std::uint64_t h = sim_detail::mix64(noise_key, static_cast<std::uint64_t>(v) * 65536U + static_cast<std::uint64_t>(u));
      if (colour) {
        // OpenCV's channel order: B, G, R.
        row[3 * u + 0] = to_byte(tone(sum[2] * 63.75F) + sigma * pixel_noise(sim_detail::mix64(h, 0)));
        row[3 * u + 1] = to_byte(tone(sum[1] * 63.75F) + sigma * pixel_noise(sim_detail::mix64(h, 1)));
        row[3 * u + 2] = to_byte(tone(sum[0] * 63.75F) + sigma * pixel_noise(sim_detail::mix64(h, 2)));
      } else {
        const float grey = (0.299F * sum[0] + 0.587F * sum[1] + 0.114F * sum[2]) * 63.75F;
        row[u] = to_byte(tone(grey) + sigma * pixel_noise(h));
      }
    }
  });
  return image;
}

cv::Mat_<float> SyntheticGenerator::render_depth(int frame, int camera) const {
  require(frame >= 0 && frame < options_.frames, "frame", "a frame index inside the sequence");
  const PinholeCamera cam = calibration_.camera(camera).camera;
  const FrameScene scene(*scene_, actor_boxes(frame));
  const ViewCaster caster(scene, T_world_camera(frame, camera), cam);
  cv::Mat_<float> depth(cam.height, cam.width, 0.0F);
  parallel_for(cam.height, options_.threads, [&](int v) {
    float* row = depth[v];
    for (int u = 0; u < cam.width; ++u) {
      // With the ray's camera-frame z component 1, the ray parameter is the depth itself.
      const auto hit = caster.cast(u, v, caster.direction(u, v));
      row[u] = hit ? static_cast<float>(hit->t) : 0.0F;
    }
  });
  return depth;
}

std::vector<LidarPoint> SyntheticGenerator::render_scan(int frame) const {
  require(frame >= 0 && frame < options_.frames, "frame", "a frame index inside the sequence");
  if (std::find(options_.dropped_scans.begin(), options_.dropped_scans.end(), frame) != options_.dropped_scans.end()) {
    return {};
  }
  const SimLidarOptions& lo = options_.lidar;
  const FrameScene scene(*scene_, actor_boxes(frame));
  const Eigen::Isometry3d T_world_lidar = pose(frame) * lo.T_cam0_lidar;
  const Eigen::Matrix3d R = T_world_lidar.linear();
  const Eigen::Vector3d origin = T_world_lidar.translation();
  const std::vector<double> elevations = lo.elevations_deg();
  const int columns = static_cast<int>(std::lround(360.0 / lo.azimuth_step_deg));
  const std::uint64_t key = sim_detail::mix64(options_.seed, static_cast<std::uint64_t>(frame), 0x11DA5ULL);
  std::vector<std::vector<LidarPoint>> rings(elevations.size());
  const auto beam_direction = [](double elevation, double azimuth) {
    return Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                           std::sin(elevation));
  };
  // the beams' true elevations: the nominal ones off by the calibration's error, the same in every frame
  std::vector<double> fired(elevations.size());
  for (std::size_t b = 0; b < elevations.size(); ++b) {
    const double error = lo.beam_elevation_sigma_deg > 0.0
                             ? lo.beam_elevation_sigma_deg *
                                   sim_detail::gaussian(sim_detail::mix64(options_.seed, b, 0xBEA4E1ULL))
                             : 0.0;
    fired[b] = (elevations[b] + lo.elevation_offset_deg + error) * kDeg;
  }
  parallel_for(static_cast<int>(elevations.size()), options_.threads, [&](int b) {
    const double e = elevations[static_cast<std::size_t>(b)] * kDeg;
    const double e_fired = fired[static_cast<std::size_t>(b)];
    auto& ring = rings[static_cast<std::size_t>(b)];
    ring.reserve(static_cast<std::size_t>(columns));
    for (int k = 0; k < columns; ++k) {
      // Rings sweep from straight behind, counter-clockwise seen from above (as KITTI's scans).
      const double azimuth = -std::numbers::pi + (k + 0.5) * 2.0 * std::numbers::pi / columns;
      // the point is computed along the nominal direction, the beam travels along the fired one
      const Eigen::Vector3d dir = beam_direction(e, azimuth), d = R * beam_direction(e_fired, azimuth);
      const auto hit = scene.intersect(origin, d, lo.max_range);
      if (!hit || hit->t < lo.min_range) continue;
      const std::uint64_t h = sim_detail::mix64(key, static_cast<std::uint64_t>(b) * 100000U + static_cast<std::uint64_t>(k));
      if (lo.dropout > 0.0 && sim_detail::unit64(sim_detail::mix64(h, 7)) < lo.dropout) continue;
      const SurfacePoint surface = scene.surface(*hit, origin, d);
      double range = hit->t + (lo.range_noise_sigma > 0.0 ? lo.range_noise_sigma * sim_detail::gaussian(h) : 0.0);
      if (lo.foliage_penetration > 0.0 && surface.kind == SurfaceKind::foliage) {
        // half-normal with the given mean: the beam goes some way into the leaves before it returns
        const double depth = std::abs(sim_detail::gaussian(sim_detail::mix64(h, 11)));
        range += lo.foliage_penetration * std::sqrt(std::numbers::pi / 2.0) * depth;
      }
      const Rgb a = sim_detail::albedo(surface, 0.003 * hit->t);
      const Eigen::Vector3d p = range * dir;
      ring.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()),
                      std::clamp(0.299F * a.r + 0.587F * a.g + 0.114F * a.b, 0.0F, 1.0F)});
    }
  });
  std::vector<LidarPoint> scan;
  std::size_t total = 0;
  for (const auto& r : rings) total += r.size();
  scan.reserve(total);
  for (const auto& r : rings) scan.insert(scan.end(), r.begin(), r.end());
  return scan;
}

SyntheticFrame SyntheticGenerator::render(int frame) const {
  SyntheticFrame f;
  f.index = frame;
  f.timestamp = timestamp(frame);
  f.T_world_cam0 = pose(frame);
  for (int c = 0; c < 4; ++c) {
    if (options_.cameras[static_cast<std::size_t>(c)]) f.images[static_cast<std::size_t>(c)] = render_image(frame, c);
  }
  if (options_.render_depth) f.depth = render_depth(frame, options_.depth_camera);
  f.scan = render_scan(frame);
  return f;
}

SyntheticSequence generate_sequence(const SyntheticOptions& options) {
  const SyntheticGenerator generator(options);
  SyntheticSequence seq;
  seq.options = generator.options();
  seq.calibration = generator.calibration();
  seq.frames.reserve(static_cast<std::size_t>(generator.frame_count()));
  for (int i = 0; i < generator.frame_count(); ++i) seq.frames.push_back(generator.render(i));
  return seq;
}

void fit_loop(SyntheticOptions& options, int laps) {
  require(laps >= 1, "--laps", "at least 1 lap");
  options.path.kind = PathKind::loop;
  options.path.loop_laps = laps;
  const double perimeter = (options.frames - 1) * options.step() / laps;
  const double radius = std::max(12.0, std::min(options.path.loop_corner_radius, perimeter / (2.0 * std::numbers::pi)));
  options.path.loop_corner_radius = radius;
  if (perimeter < 2.0 * std::numbers::pi * radius) {
    throw ConfigError("--frames", fmt::format("at least {} frames for {} lap(s) of a loop (corners of {:g} m radius)",
                                              static_cast<int>(std::ceil(laps * 2.0 * std::numbers::pi * radius /
                                                                         options.step())) + 1,
                                              laps, radius));
  }
}

}  // namespace rgbl
