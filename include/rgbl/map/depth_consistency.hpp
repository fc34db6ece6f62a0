#pragma once
// Whether a landmark's LiDAR depths agree with what its keyframes' images alone say about it. Leaves
// take a LiDAR beam some way in before it returns, by another distance on every scan; the dilation's
// nearest sample does not undo that on the side of a hedge. Depth rows that disagree with the
// landmark's own parallax are weighed less, so that its position follows the images there. Measured,
// it mostly flags distant landmarks whose depth came from the background across an edge; a hedge's
// bias is usually within its parallax's sigma (docs/accuracy.md).

#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"

namespace rgbl {

// The factor on a landmark's depth sigmas from its keyframes' observations (call under the map's lock):
// - its position triangulated from the keypoints' rays alone, each weighted by its pyramid level's
//   pixel sigma at the landmark's distance, with that triangulation's covariance;
// - for each of the m keyframes with depth, e_i = depth_i - z_i, z_i the triangulated point's camera z
//   there, v_i that z's variance and sigma_i the depth's sigma;
// - when sum e_i^2 / (sigma_i^2 + v_i) exceeds chi2(m) at 95 %: sqrt(mean (e_i^2 - v_i) / sigma_i^2),
//   at least 1 (the spread the depths need to explain what the triangulation does not), else 1.
//   Also 1 with fewer than three keyframes or two with depth, or where the rays do not pin the point
//   in all three axes (parallel).
double depth_consistency_scale(const Map& map, const Landmark& landmark, const PinholeCamera& camera);

// chi2 with `dof` degrees of freedom at 95 % (Wilson-Hilferty; within 1 % from 2 up, 4 % at 1).
double chi2_95(double dof);

}  // namespace rgbl
