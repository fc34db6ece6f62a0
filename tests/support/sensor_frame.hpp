#pragma once
// One camera of a loaded frame as the tracker takes it: the image of `camera` and the LiDAR scan.
// The SensorFrame views `input`'s scan: keep `input` alive while it is used.

#include "rgbl/depth/depth_source.hpp"
#include "rgbl/io/frame_input.hpp"

#include <cstddef>

namespace rgbl::test {

inline SensorFrame sensor_frame(const FrameInput& input, int camera = 0) {
  SensorFrame frame;
  frame.index = input.index;
  frame.timestamp = input.timestamp;
  frame.image = input.images[static_cast<std::size_t>(camera)];
  frame.scan = input.scan;
  return frame;
}

}  // namespace rgbl::test
