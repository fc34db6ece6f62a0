#pragma once
// The SLAM map: keyframes, landmarks, their observations, the covisibility graph and the spanning
// tree. The Map owns everything by value; keyframes and landmarks refer to each other only by stable
// integer ids (never reused), so there are no pointer cycles.
//
// Concurrency: the Map does not lock by itself. Readers take std::shared_lock on mutex(), writers
// std::unique_lock. Pointers returned by keyframe()/landmark() stay valid until that element is
// erased (storage is a deque), but must not be used after the lock that guarded the look-up is gone.

#include "rgbl/features/types.hpp"
#include "rgbl/geometry/scan_agreement.hpp"
#include "rgbl/geometry/se3.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <compare>
#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <span>
#include <vector>

namespace rgbl {

// Strong integer id: a KeyframeId cannot be passed where a LandmarkId is expected.
template <class Tag>
struct Id {
  int value = -1;
  constexpr bool valid() const { return value >= 0; }
  friend constexpr auto operator<=>(Id, Id) = default;
};
using KeyframeId = Id<struct KeyframeTag>;
using LandmarkId = Id<struct LandmarkTag>;

struct Keyframe {
  KeyframeId id;
  std::size_t frame_index = 0;
  double timestamp = 0.0;
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;
  std::vector<float> depth;           // camera z per keypoint, metres; 0 = none
  std::vector<float> depth_sigma;     // standard deviation of depth, metres; 0 when depth is 0
  // Keypoints where the depth source measured something but no usable depth (Frame::depth_refused; a
  // depth edge): a corner there may be where two surfaces cross in the image, no point in the world,
  // so triangulation leaves them out. Empty = none known.
  std::vector<bool> depth_refused;
  std::vector<LandmarkId> landmarks;  // per keypoint; invalid = none
  std::map<KeyframeId, int> covisibility;  // other keyframe -> number of shared landmarks
  KeyframeId parent;                        // spanning tree; invalid for the root
  // The road under the camera from its LiDAR scan: (n, d) of the plane n . x = d in the camera frame
  // (n pointing down, d the camera's height); none without a scan or a road in it.
  std::optional<Eigen::Vector4d> road;
  // The motion tracking measured from the keyframe before it (its reference when it was made):
  // T_cam_previous = T_cam_world * inv(T_previous_world) at insertion; local BA keeps to it. None for a
  // map's first. Erasing the previous one hands over its own previous, the motions composed.
  KeyframeId previous;
  Eigen::Isometry3d T_cam_previous = Eigen::Isometry3d::Identity();
  // A subsample of its LiDAR scan in its camera frame (null without a scan; local mapping releases it
  // once the next keyframe is registered onto it), and the motion from `previous` that its scan
  // registered onto the previous one's measures (none until local mapping measured it, or when the
  // registration was not a clear optimum): local BA keeps to it too
  // (KeyframePairOptions::lidar_sigma_translation). Composed like T_cam_previous when a keyframe
  // between is erased.
  std::shared_ptr<const ScanSample> scan;
  std::optional<Eigen::Isometry3d> T_cam_previous_lidar;

  Eigen::Vector3d center() const { return T_cam_world.inverse().translation(); }
  int landmark_count() const;
  // Median of the usable keypoint depths (depth_sigma > 0), metres; 0 when there are none.
  double median_depth() const;
  // Landmarks seen at least min_observations times.
  int tracked_landmarks(int min_observations, const class Map& map) const;
};

struct Landmark {
  LandmarkId id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Descriptor descriptor{};
  std::map<KeyframeId, int> observations;  // keyframe -> keypoint index
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // mean viewing direction (landmark - centre), unit
  double min_distance = 0.0, max_distance = 0.0;     // scale-invariance range
  KeyframeId reference_keyframe;
  KeyframeId first_keyframe;
  int visible = 1;  // frames in which it was predicted visible
  int found = 1;    // frames in which it was matched
  // How far its keyframes' depths disagree with their parallax beyond their sigmas (>= 1; set by local
  // mapping, LocalMappingOptions::depth_consistency): every depth row of this landmark in bundle
  // adjustment is weighed by its sigma times this (the tracker's rows are not: see docs/accuracy.md).
  double depth_sigma_scale = 1.0;

  double found_ratio() const { return static_cast<double>(found) / visible; }
  // Pyramid level at which a keypoint of this landmark should appear at `distance`.
  int predict_level(double distance, int levels, double scale_factor) const;
};

struct MapOptions {
  int levels = 8;              // pyramid levels of the extractor
  double scale_factor = 1.2;   // scale between levels

  void validate() const;
};

class Map {
 public:
  explicit Map(MapOptions options = {});

  std::shared_mutex& mutex() const { return mutex_; }
  const MapOptions& options() const { return options_; }

  // Takes the keyframe (its id, covisibility and parent are assigned here); its landmark slots may
  // already name landmarks, in which case call add_observation for them.
  KeyframeId add_keyframe(Keyframe keyframe);
  LandmarkId add_landmark(const Eigen::Vector3d& position, KeyframeId reference);
  void add_observation(LandmarkId landmark, KeyframeId keyframe, int keypoint);
  // Removes one observation; a landmark left with no observation is erased.
  void erase_observation(LandmarkId landmark, KeyframeId keyframe);
  void erase_landmark(LandmarkId landmark);
  // Removes the keyframe and its observations and re-attaches its children in the spanning tree.
  // Its pose relative to its parent is kept so that frames tracked against it keep a pose.
  void erase_keyframe(KeyframeId keyframe);
  // Duplicate fusion: every observation of `from` moves to `into` (unless that keyframe already sees
  // `into`), then `from` is erased.
  void replace_landmark(LandmarkId from, LandmarkId into);

  // Recomputes the representative descriptor (the one with the least median distance to the others)
  // and the viewing direction and distance range.
  void update_landmark(LandmarkId landmark);
  // Recomputes the covisibility weights of a keyframe (and the reverse edges) from its landmarks;
  // sets the parent to the strongest neighbour when it has none.
  void update_covisibility(KeyframeId keyframe);
  // The n neighbours with the largest weights, strongest first (ties by id).
  std::vector<KeyframeId> best_covisible(KeyframeId keyframe, std::size_t n, int min_weight = 1) const;
  // The keyframe itself followed by its n best covisible ones: the window local BA adjusts and the
  // region loop closing searches and fuses.
  std::vector<KeyframeId> neighbourhood(KeyframeId keyframe, std::size_t n) const;

  Keyframe* keyframe(KeyframeId id);
  const Keyframe* keyframe(KeyframeId id) const;
  Landmark* landmark(LandmarkId id);
  const Landmark* landmark(LandmarkId id) const;

  // Pose of a keyframe, also of an erased one (through the parents it was attached to).
  std::optional<Eigen::Isometry3d> keyframe_pose(KeyframeId id) const;

  std::size_t keyframe_count() const { return keyframe_count_; }
  std::size_t landmark_count() const { return landmark_count_; }
  // Ids of the live keyframes / landmarks in increasing order.
  std::vector<KeyframeId> keyframe_ids() const;
  std::vector<LandmarkId> landmark_ids() const;
  // The distinct landmarks observed by any of `keyframes` (erased keyframes are skipped), ascending.
  std::vector<LandmarkId> landmarks_seen_by(std::span<const KeyframeId> keyframes) const;
  KeyframeId last_keyframe_id() const;

  void clear();

 private:
  struct ErasedKeyframe {
    KeyframeId parent;
    Eigen::Isometry3d T_cam_parent = Eigen::Isometry3d::Identity();
  };

  MapOptions options_;
  mutable std::shared_mutex mutex_;
  std::deque<std::optional<Keyframe>> keyframes_;   // index = id
  std::deque<std::optional<Landmark>> landmarks_;   // index = id
  std::map<int, ErasedKeyframe> erased_keyframes_;
  std::size_t keyframe_count_ = 0, landmark_count_ = 0;
};

}  // namespace rgbl
