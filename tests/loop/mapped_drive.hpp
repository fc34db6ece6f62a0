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

// Landmarks of the map's first keyframe found in fewer than min_found_ratio of the frames that
// predicted them visible. 04's first frame has a car driving ahead: its points, found once and
// predicted a dozen times, stayed in the map until 2026-12-05 (341 of 860 after 30 frames) and a loop
// verification aligned a revisit to them. Local mapping culls by that ratio while the next three
// keyframes are made, so a few that fall below it later remain.
inline int unfound_first_keyframe_landmarks(const Map& map, double min_found_ratio) {
  const std::vector<KeyframeId> keyframes = map.keyframe_ids();
  int unfound = 0;
  for (const LandmarkId id : map.landmark_ids()) {
    const Landmark& l = *map.landmark(id);
    if (l.first_keyframe == keyframes.front() && l.found_ratio() < min_found_ratio) ++unfound;
  }
  return unfound;
}

// Tracks the first `frames` frames of `sequence` (camera 0, LiDAR depth).
inline Mapped map_drive(const std::unique_ptr<Sequence>& sequence, std::size_t frames,
                        const SystemOptions& options = {}) {
  return track_frames(sequence->calibration().camera(0), std::min(frames, sequence->size()),
                      [&](std::size_t i) { return sequence->load(i); }, options);
}

}  // namespace rgbl::test
