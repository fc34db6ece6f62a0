#pragma once
// Surface colours of the synthetic street (internal to rgbl::sim).

#include "rgbl/sim/scene.hpp"

namespace rgbl::sim_detail {

struct Rgb {
  float r = 0.0F, g = 0.0F, b = 0.0F;
};

// Albedo (0..1 per channel) at a surface point. `footprint` is the size in metres of the patch one
// sample stands for: detail smaller than that is replaced by its mean, and an infinite footprint
// gives the surface's plain colour (the "untextured" look).
Rgb albedo(const SurfacePoint& s, double footprint);

// Whether sunlight passes a tree's crown at world point p: blobs of leaf gaps covering about `share`
// of the crown (a function of the point alone, so the dapples stay put from frame to frame).
bool leaf_gap(const Eigen::Vector3d& p, double share);

}  // namespace rgbl::sim_detail
