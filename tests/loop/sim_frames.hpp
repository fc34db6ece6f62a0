#pragma once
// A frame of the simulator as the loop tests feed it: camera 0's image and the LiDAR scan.

#include "rgbl/io/frame_input.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <cstddef>

namespace rgbl::test {

inline FrameInput render_frame(const SyntheticGenerator& generator, int i) {
  FrameInput f;
  f.index = static_cast<std::size_t>(i);
  f.timestamp = generator.timestamp(i);
  f.images[0] = generator.render_image(i, 0);
  f.scan = generator.render_scan(i);
  return f;
}

}  // namespace rgbl::test
