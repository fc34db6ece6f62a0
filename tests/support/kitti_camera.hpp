#pragma once
// The rectified KITTI seq 04 camera (cam0) that synthetic tests project into.

#include "rgbl/geometry/camera.hpp"

namespace rgbl::test {

inline PinholeCamera kitti_camera() {
  PinholeCamera c;
  c.fx = c.fy = 707.0912;
  c.cx = 601.8873;
  c.cy = 183.1104;
  c.width = 1226;
  c.height = 370;
  return c;
}

}  // namespace rgbl::test
