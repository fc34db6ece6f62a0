#pragma once
// Local mapping for one new keyframe: observations, new landmarks from depth, landmark culling,
// duplicate fusion, local bundle adjustment and keyframe culling. The heavy solve runs without the map
// lock (on a copy), so tracking can read the map meanwhile when mapping has its own thread.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"
#include "rgbl/tracking/options.hpp"

#include <atomic>
#include <vector>

namespace rgbl {

struct LocalMappingStats {
  int new_landmarks = 0;
  int culled_landmarks = 0;
  int fused_landmarks = 0;
  int culled_keyframes = 0;
  int ba_outliers = 0;
  double ba_ms = 0.0;
};

class LocalMapper {
 public:
  LocalMapper(Map& map, const PinholeCamera& camera, LocalMappingOptions options);

  // Processes a keyframe already added to the map; takes the map lock itself.
  LocalMappingStats process(KeyframeId keyframe);

  // Asks a running bundle adjustment to stop early (e.g. when a new keyframe is waiting).
  void request_abort() { abort_ = true; }

 private:
  void associate(KeyframeId keyframe);
  int create_depth_landmarks(KeyframeId keyframe);
  int cull_landmarks(KeyframeId keyframe);
  int fuse(KeyframeId keyframe);
  int local_bundle_adjustment(KeyframeId keyframe, double& elapsed_ms);
  int cull_keyframes(KeyframeId keyframe);

  Map& map_;
  PinholeCamera camera_;
  LocalMappingOptions options_;
  std::vector<LandmarkId> recent_landmarks_;
  std::atomic<bool> abort_{false};
};

}  // namespace rgbl
