#pragma once
// Where a keypoint's ray can appear in another view: the image of the ray from a nearest depth to
// infinity. Local mapping's triangulation searches along it; the tracker tests motions against it.

#include "rgbl/geometry/camera.hpp"

#include <Eigen/Geometry>

#include <optional>
#include <utility>

namespace rgbl {

// Clips the segment a-b to the rectangle [lo, hi] (Liang-Barsky); false when nothing is left.
bool clip_segment(Eigen::Vector2d& a, Eigen::Vector2d& b, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

// The keypoint's ray (z = 1 in its own camera) seen from the other camera: the projections of its
// points from depth min_depth to infinity that lie in front of the other camera, as a segment (the
// point at infinity, then the nearest) clipped to the image widened by `margin`; none when nothing
// of it is in front or in the widened image.
std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> epipolar_segment(const Eigen::Isometry3d& T_other_own,
                                                                           const Eigen::Vector3d& ray, double min_depth,
                                                                           const PinholeCamera& camera, double margin);

// Distance from p to the segment a-b (to a when they coincide).
double distance_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b);

}  // namespace rgbl
