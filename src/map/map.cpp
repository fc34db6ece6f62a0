#include "rgbl/map/map.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rgbl {

int Keyframe::landmark_count() const {
  return static_cast<int>(std::count_if(landmarks.begin(), landmarks.end(), [](LandmarkId l) { return l.valid(); }));
}

double Keyframe::median_depth() const {
  std::vector<float> usable;
  for (std::size_t i = 0; i < depth.size(); ++i) {
    if (depth_sigma[i] > 0.0F) usable.push_back(depth[i]);
  }
  if (usable.empty()) return 0.0;
  const auto middle = usable.begin() + static_cast<std::ptrdiff_t>(usable.size() / 2);
  std::nth_element(usable.begin(), middle, usable.end());
  return *middle;
}

int Keyframe::tracked_landmarks(int min_observations, const Map& map) const {
  int n = 0;
  for (const LandmarkId landmark_id : landmarks) {
    const Landmark* l = landmark_id.valid() ? map.landmark(landmark_id) : nullptr;
    if (l != nullptr && static_cast<int>(l->observations.size()) >= min_observations) ++n;
  }
  return n;
}

int Landmark::predict_level(double distance, int levels, double scale_factor) const {
  if (distance <= 0.0) return 0;
  const double ratio = max_distance / distance;
  int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(scale_factor)));
  return std::clamp(level, 0, levels - 1);
}

void MapOptions::validate() const {
  require(levels >= 1, "map.levels", ">= 1");
  require(scale_factor > 1.0, "map.scale_factor", "> 1");
}

Map::Map(MapOptions options) : options_(options) { options_.validate(); }

KeyframeId Map::add_keyframe(Keyframe keyframe) {
  keyframe.id = KeyframeId{static_cast<int>(keyframes_.size())};
  keyframe.covisibility.clear();
  keyframe.parent = KeyframeId{};
  keyframe.landmarks.resize(keyframe.keypoints.size());
  keyframe.depth.resize(keyframe.keypoints.size(), 0.0F);
  keyframe.depth_sigma.resize(keyframe.keypoints.size(), 0.0F);
  const KeyframeId id = keyframe.id;
  keyframes_.emplace_back(std::move(keyframe));
  ++keyframe_count_;
  return id;
}

LandmarkId Map::add_landmark(const Eigen::Vector3d& position, KeyframeId reference) {
  Landmark l;
  l.id = LandmarkId{static_cast<int>(landmarks_.size())};
  l.position = position;
  l.reference_keyframe = reference;
  l.first_keyframe = reference;
  landmarks_.emplace_back(std::move(l));
  ++landmark_count_;
  return landmarks_.back()->id;
}

void Map::add_observation(LandmarkId landmark_id, KeyframeId keyframe_id, int keypoint) {
  Landmark* l = landmark(landmark_id);
  Keyframe* k = keyframe(keyframe_id);
  if (l == nullptr || k == nullptr || keypoint < 0 || keypoint >= static_cast<int>(k->landmarks.size())) return;
  // One keypoint holds one landmark and a landmark is seen once per keyframe.
  if (const auto it = l->observations.find(keyframe_id); it != l->observations.end()) {
    if (it->second == keypoint) return;
    k->landmarks[static_cast<std::size_t>(it->second)] = LandmarkId{};
  }
  LandmarkId& slot = k->landmarks[static_cast<std::size_t>(keypoint)];
  if (slot.valid() && slot != landmark_id) {
    if (Landmark* old = landmark(slot)) old->observations.erase(keyframe_id);
  }
  slot = landmark_id;
  l->observations[keyframe_id] = keypoint;
}

void Map::erase_observation(LandmarkId landmark_id, KeyframeId keyframe_id) {
  Landmark* l = landmark(landmark_id);
  if (l == nullptr) return;
  const auto it = l->observations.find(keyframe_id);
  if (it == l->observations.end()) return;
  if (Keyframe* k = keyframe(keyframe_id)) k->landmarks[static_cast<std::size_t>(it->second)] = LandmarkId{};
  l->observations.erase(it);
  if (l->observations.empty()) {
    erase_landmark(landmark_id);
  } else if (l->reference_keyframe == keyframe_id) {
    l->reference_keyframe = l->observations.begin()->first;
  }
}

void Map::erase_landmark(LandmarkId landmark_id) {
  Landmark* l = landmark(landmark_id);
  if (l == nullptr) return;
  for (const auto& [kf, index] : l->observations) {
    if (Keyframe* k = keyframe(kf)) k->landmarks[static_cast<std::size_t>(index)] = LandmarkId{};
  }
  landmarks_[static_cast<std::size_t>(landmark_id.value)].reset();
  --landmark_count_;
}

void Map::erase_keyframe(KeyframeId keyframe_id) {
  Keyframe* k = keyframe(keyframe_id);
  if (k == nullptr) return;
  // Remove observations (may erase landmarks).
  for (std::size_t i = 0; i < k->landmarks.size(); ++i) {
    if (k->landmarks[i].valid()) erase_observation(k->landmarks[i], keyframe_id);
  }
  // Remove covisibility edges.
  for (const auto& [other, weight] : k->covisibility) {
    if (Keyframe* o = keyframe(other)) o->covisibility.erase(keyframe_id);
  }
  // Re-attach children: to their strongest remaining older neighbour, or to this keyframe's parent.
  // A parent is always older than its child, so the tree never closes a cycle.
  KeyframeId new_parent = k->parent;
  for (auto& slot : keyframes_) {
    // the motion measured into this keyframe is carried on to the one measured from it
    if (slot && slot->previous == keyframe_id) {
      slot->previous = k->previous;
      slot->T_cam_previous = slot->T_cam_previous * k->T_cam_previous;
      if (slot->T_cam_previous_lidar && k->T_cam_previous_lidar) {
        slot->T_cam_previous_lidar = *slot->T_cam_previous_lidar * *k->T_cam_previous_lidar;
      } else {
        slot->T_cam_previous_lidar.reset();
      }
    }
    if (!slot || slot->parent != keyframe_id) continue;
    KeyframeId best = new_parent;
    int best_weight = -1;
    for (const auto& [other, weight] : slot->covisibility) {
      if (other != keyframe_id && other < slot->id && weight > best_weight && keyframe(other) != nullptr) {
        best = other;
        best_weight = weight;
      }
    }
    slot->parent = best;
  }
  ErasedKeyframe erased;
  erased.parent = new_parent;
  if (const Keyframe* p = keyframe(new_parent)) erased.T_cam_parent = k->T_cam_world * p->T_cam_world.inverse();
  else erased.T_cam_parent = k->T_cam_world;  // root: parent is the world itself
  erased_keyframes_[keyframe_id.value] = erased;
  keyframes_[static_cast<std::size_t>(keyframe_id.value)].reset();
  --keyframe_count_;
}

void Map::replace_landmark(LandmarkId from, LandmarkId into) {
  if (from == into) return;
  Landmark* f = landmark(from);
  Landmark* t = landmark(into);
  if (f == nullptr || t == nullptr) return;
  const auto observations = f->observations;
  const int visible = f->visible, found = f->found;
  erase_landmark(from);
  t = landmark(into);
  for (const auto& [kf, index] : observations) {
    if (t->observations.count(kf) == 0) add_observation(into, kf, index);
  }
  t->visible += visible;
  t->found += found;
  update_landmark(into);
}

void Map::update_landmark(LandmarkId landmark_id) {
  Landmark* l = landmark(landmark_id);
  if (l == nullptr || l->observations.empty()) return;
  std::vector<const Descriptor*> descriptors;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  descriptors.reserve(l->observations.size());
  for (const auto& [kf, index] : l->observations) {
    const Keyframe* k = keyframe(kf);
    if (k == nullptr) continue;
    descriptors.push_back(&k->descriptors[static_cast<std::size_t>(index)]);
    normal += (l->position - k->center()).normalized();
  }
  if (descriptors.empty()) return;
  // Representative descriptor: least median distance to the others.
  const std::size_t n = descriptors.size();
  int best_median = std::numeric_limits<int>::max();
  std::size_t best = 0;
  std::vector<int> distances(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) distances[j] = hamming_distance(*descriptors[i], *descriptors[j]);
    std::nth_element(distances.begin(), distances.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), distances.end());
    const int median = distances[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  l->descriptor = *descriptors[best];
  if (normal.norm() > 0.0) l->normal = normal.normalized();
  // Distance range from the reference keyframe's observation and its pyramid level.
  const Keyframe* ref = keyframe(l->reference_keyframe);
  if (ref == nullptr) ref = keyframe(l->observations.begin()->first);
  if (ref == nullptr) return;
  const auto it = l->observations.find(ref->id);
  if (it == l->observations.end()) return;
  const double distance = (l->position - ref->center()).norm();
  const int level = ref->keypoints[static_cast<std::size_t>(it->second)].level;
  const double level_scale = std::pow(options_.scale_factor, level);
  l->max_distance = distance * level_scale;
  l->min_distance = l->max_distance / std::pow(options_.scale_factor, options_.levels - 1);
}

void Map::update_covisibility(KeyframeId keyframe_id) {
  Keyframe* k = keyframe(keyframe_id);
  if (k == nullptr) return;
  std::map<KeyframeId, int> counts;
  for (const LandmarkId id : k->landmarks) {
    const Landmark* l = id.valid() ? landmark(id) : nullptr;
    if (l == nullptr) continue;
    for (const auto& [kf, index] : l->observations) {
      if (kf != keyframe_id) ++counts[kf];
    }
  }
  // Drop stale reverse edges, then write both directions.
  for (const auto& [other, weight] : k->covisibility) {
    if (counts.count(other) == 0) {
      if (Keyframe* o = keyframe(other)) o->covisibility.erase(keyframe_id);
    }
  }
  k->covisibility = counts;
  // A keyframe without a parent hangs from its strongest older neighbour (older: the tree stays
  // acyclic; with mapping in its own thread, newer keyframes may already share more landmarks). The
  // first keyframe of a map has none and stays a root.
  KeyframeId strongest;
  int strongest_weight = 0;
  for (const auto& [other, weight] : counts) {
    if (Keyframe* o = keyframe(other)) o->covisibility[keyframe_id] = weight;
    if (other < keyframe_id && weight > strongest_weight) {
      strongest_weight = weight;
      strongest = other;
    }
  }
  if (!k->parent.valid() && strongest.valid()) k->parent = strongest;
}

std::vector<KeyframeId> Map::best_covisible(KeyframeId keyframe_id, std::size_t n, int min_weight) const {
  const Keyframe* k = keyframe(keyframe_id);
  if (k == nullptr) return {};
  std::vector<std::pair<int, KeyframeId>> sorted;
  for (const auto& [other, weight] : k->covisibility) {
    if (weight >= min_weight && keyframe(other) != nullptr) sorted.emplace_back(weight, other);
  }
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::vector<KeyframeId> out;
  for (std::size_t i = 0; i < sorted.size() && i < n; ++i) out.push_back(sorted[i].second);
  return out;
}

std::vector<KeyframeId> Map::neighbourhood(KeyframeId keyframe, std::size_t n) const {
  std::vector<KeyframeId> window = {keyframe};
  for (const KeyframeId k : best_covisible(keyframe, n)) window.push_back(k);
  return window;
}

Keyframe* Map::keyframe(KeyframeId id) {
  if (!id.valid() || static_cast<std::size_t>(id.value) >= keyframes_.size()) return nullptr;
  auto& slot = keyframes_[static_cast<std::size_t>(id.value)];
  return slot ? &*slot : nullptr;
}
const Keyframe* Map::keyframe(KeyframeId id) const { return const_cast<Map*>(this)->keyframe(id); }

Landmark* Map::landmark(LandmarkId id) {
  if (!id.valid() || static_cast<std::size_t>(id.value) >= landmarks_.size()) return nullptr;
  auto& slot = landmarks_[static_cast<std::size_t>(id.value)];
  return slot ? &*slot : nullptr;
}
const Landmark* Map::landmark(LandmarkId id) const { return const_cast<Map*>(this)->landmark(id); }

std::optional<Eigen::Isometry3d> Map::keyframe_pose(KeyframeId id) const {
  Eigen::Isometry3d T_cam_kf = Eigen::Isometry3d::Identity();  // accumulated: T_id_current
  KeyframeId current = id;
  for (std::size_t guard = 0; guard <= keyframes_.size(); ++guard) {
    if (const Keyframe* k = keyframe(current)) return T_cam_kf * k->T_cam_world;
    const auto it = erased_keyframes_.find(current.value);
    if (it == erased_keyframes_.end()) return std::nullopt;
    T_cam_kf = T_cam_kf * it->second.T_cam_parent;
    if (!it->second.parent.valid()) return T_cam_kf;
    current = it->second.parent;
  }
  return std::nullopt;
}

std::vector<KeyframeId> Map::keyframe_ids() const {
  std::vector<KeyframeId> ids;
  ids.reserve(keyframe_count_);
  for (const auto& slot : keyframes_) {
    if (slot) ids.push_back(slot->id);
  }
  return ids;
}

std::vector<LandmarkId> Map::landmarks_seen_by(std::span<const KeyframeId> keyframes) const {
  std::vector<LandmarkId> seen;
  for (const KeyframeId id : keyframes) {
    const Keyframe* kf = keyframe(id);
    if (kf == nullptr) continue;
    for (const LandmarkId l : kf->landmarks) {
      if (l.valid()) seen.push_back(l);
    }
  }
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
  return seen;
}

std::vector<LandmarkId> Map::landmark_ids() const {
  std::vector<LandmarkId> ids;
  ids.reserve(landmark_count_);
  for (const auto& slot : landmarks_) {
    if (slot) ids.push_back(slot->id);
  }
  return ids;
}

KeyframeId Map::last_keyframe_id() const {
  for (auto it = keyframes_.rbegin(); it != keyframes_.rend(); ++it) {
    if (*it) return (*it)->id;
  }
  return KeyframeId{};
}

void Map::clear() {
  keyframes_.clear();
  landmarks_.clear();
  erased_keyframes_.clear();
  keyframe_count_ = 0;
  landmark_count_ = 0;
}

}  // namespace rgbl
