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
  int triangulated_landmarks = 0;  // LocalMappingOptions::triangulation
  int culled_landmarks = 0;
  int fused_landmarks = 0;
  int culled_keyframes = 0;  // both rules together
  int culled_revisited = 0;  // of those, by revisit (LocalMappingOptions::place_culling)
  int ba_outliers = 0;
  double ba_ms = 0.0;
};

// Landmarks at the keyframe's keypoints with depth that have none, nearest first, at most max_points
// (RGB-D: a metric point needs no second view). The caller holds the map lock exclusively.
std::vector<LandmarkId> create_depth_landmarks(Map& map, const PinholeCamera& camera, KeyframeId keyframe,
                                               int max_points);

class LocalMapper {
 public:
  LocalMapper(Map& map, const PinholeCamera& camera, LocalMappingOptions options);

  // Processes a keyframe already added to the map; takes the map lock itself. created_with_keyframe:
  // depth landmarks the caller made with the keyframe (create_depth_landmarks, threaded mapping: so
  // that tracking finds the new points at the next frame, not once mapping catches up); they count
  // against max_new_depth_points, and keypoints left without a landmark by culling get new ones.
  LocalMappingStats process(KeyframeId keyframe, const std::vector<LandmarkId>& created_with_keyframe = {});

  // A map's first keyframe is made by tracking's initialisation, not by process(): its landmarks are
  // put under the found-ratio rule of every later keyframe's, checked as the next three keyframes are
  // mapped. Without it a point on a car driving ahead in the first frame, predicted visible in a dozen
  // frames and found in no frame after its own, stays in the map for good, and a loop verification can
  // align a revisit to that car rather than to the street (2026-12-05). The min_observations rule is
  // left out: it also takes the points the return of a loop to the drive's start needs (the
  // simulator's loop tests lose their closures). Takes the map lock itself.
  void watch_initial(KeyframeId keyframe);

  // Asks a running bundle adjustment to stop early (e.g. when a new keyframe is waiting).
  void request_abort() { abort_ = true; }

 private:
  void associate(KeyframeId keyframe);
  int cull_landmarks(KeyframeId keyframe);
  int fuse(KeyframeId keyframe);
  // Registers the keyframe's scan onto its previous keyframe's and keeps the motion as
  // Keyframe::T_cam_previous_lidar where it is a clear optimum near the tracked motion (only with
  // the LiDAR pair on). Takes the map lock itself; registers without it.
  void measure_lidar_pair(KeyframeId keyframe);
  int local_bundle_adjustment(KeyframeId keyframe, double& elapsed_ms);
  int cull_keyframes(KeyframeId keyframe);
  int cull_revisited(KeyframeId keyframe);

  Map& map_;
  PinholeCamera camera_;
  LocalMappingOptions options_;
  // Landmarks under the culling rules until three keyframes after their first.
  struct WatchedLandmark {
    LandmarkId id;
    bool initial = false;  // of a map's first keyframe: the found-ratio rule only
  };
  std::vector<WatchedLandmark> recent_landmarks_;
  std::atomic<bool> abort_{false};
};

}  // namespace rgbl
