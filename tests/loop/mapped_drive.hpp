#pragma once
// A real drive tracked with default settings for the loop tests: the map is the result.

#include "support/sensor_frame.hpp"
#include "rgbl/depth/sources.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/io/sequence.hpp"
#include "rgbl/tracking/system.hpp"

#include <algorithm>
#include <memory>
#include <vector>

namespace rgbl::test {

struct Mapped {
  CameraCalibration calibration;
  std::unique_ptr<System> system;
  std::vector<TrackResult> results;
};

// Tracks `count` frames, load(i) giving each as a FrameInput (by value or by reference; camera 0's
// image and the LiDAR scan are used), with LiDAR depth and the default ORB extractor.
template <class Load>
Mapped track_frames(const CameraCalibration& calibration, std::size_t count, Load load, const SystemOptions& options = {}) {
  Mapped m;
  m.calibration = calibration;
  DepthSourceContext depth;
  depth.calibration = m.calibration;
  m.system = std::make_unique<System>(options, m.calibration, make_lidar_source({}, depth), make_orb_extractor({}));
  for (std::size_t i = 0; i < count; ++i) {
    const FrameInput& input = load(i);  // a temporary lives until the end of this iteration
    SensorFrame frame = sensor_frame(input);
    frame.index = i;
    m.results.push_back(m.system->track(frame));
  }
  m.system->finish();
  return m;
}

// Tracks the first `frames` frames of `sequence` (camera 0, LiDAR depth).
inline Mapped map_drive(const std::unique_ptr<Sequence>& sequence, std::size_t frames,
                        const SystemOptions& options = {}) {
  return track_frames(sequence->calibration().camera(0), std::min(frames, sequence->size()),
                      [&](std::size_t i) { return sequence->load(i); }, options);
}

}  // namespace rgbl::test
