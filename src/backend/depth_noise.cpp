#include "rgbl/backend/depth_noise.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rgbl {

void DepthNoiseModel::validate() const {
  require(sigma_min > 0.0, "depth_noise.sigma_min", "> 0");
  require(sigma_relative >= 0.0, "depth_noise.sigma_relative", ">= 0");
  require(sigma_per_pixel >= 0.0, "depth_noise.sigma_per_pixel", ">= 0");
  require(sigma_quadratic >= 0.0, "depth_noise.sigma_quadratic", ">= 0");
  require(registration_sigma_deg >= 0.0 && registration_sigma_deg < 5.0, "depth_noise.registration_sigma_deg",
          "0 (off) .. 5 deg");
  require(max_spread > 0.0, "depth_noise.max_spread", "> 0");
  require(max_spread_relative >= 0.0, "depth_noise.max_spread_relative", ">= 0");
  require(min_depth > 0.0 && max_depth > min_depth, "depth_noise.min_depth/max_depth", "0 < min_depth < max_depth");
  require(max_sigma_relative > 0.0, "depth_noise.max_sigma_relative", "> 0");
}

double DepthNoiseModel::sigma(double z, double sample_distance_px, double spread, double fx, double gradient) const {
  if (!(z >= min_depth && z <= max_depth)) return 0.0;
  if (spread > std::max(max_spread, max_spread_relative * z)) return 0.0;
  const double from_pixel = sigma_per_pixel * sample_distance_px * z * z / fx;
  const double relative = sigma_relative * z;
  const double quadratic = sigma_quadratic * z * z;
  const double registration = registration_sigma_deg * std::numbers::pi / 180.0 * fx * gradient;
  const double s = std::sqrt(sigma_min * sigma_min + relative * relative + from_pixel * from_pixel + quadratic * quadratic +
                             registration * registration);
  return s > max_sigma_relative * z ? 0.0 : s;
}

}  // namespace rgbl
