#include "matching.hpp"

#include "rgbl/features/matcher.hpp"

#include <algorithm>
#include <climits>
#include <cmath>

namespace rgbl::detail {

int match_projected(Frame& frame, std::span<const ProjectedLandmark> candidates, int max_hamming, double ratio,
                    bool check_orientation, std::vector<int>* candidate_of_keypoint, DepthGate gate) {
  const std::size_t n = frame.size();
  std::vector<int> best_distance(n, INT_MAX);
  std::vector<int> owner(n, -1);  // candidate index holding the keypoint in this call
  std::vector<int> cell;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const ProjectedLandmark& cand = candidates[c];
    frame.grid.query(cand.x, cand.y, cand.radius, cand.min_level, cand.max_level, cell);
    int best = INT_MAX, second = INT_MAX, best_index = -1, best_level = -1, second_level = -1;
    for (const int k : cell) {
      if (frame.landmarks[static_cast<std::size_t>(k)].valid() && owner[static_cast<std::size_t>(k)] < 0) continue;
      if (frame.is_moving(static_cast<std::size_t>(k))) continue;
      if (gate.sigmas > 0.0F && cand.depth > 0.0F && frame.depth[static_cast<std::size_t>(k)] > 0.0F) {
        const float gap = std::max(gate.min_gap, gate.sigmas * frame.depth_sigma[static_cast<std::size_t>(k)]);
        if (std::abs(frame.depth[static_cast<std::size_t>(k)] - cand.depth) > gap) continue;
      }
      const int d = hamming_distance(cand.descriptor, frame.descriptors[static_cast<std::size_t>(k)]);
      if (d < best) {
        second = best;
        second_level = best_level;
        best = d;
        best_index = k;
        best_level = frame.keypoints[static_cast<std::size_t>(k)].level;
      } else if (d < second) {
        second = d;
        second_level = frame.keypoints[static_cast<std::size_t>(k)].level;
      }
    }
    if (best_index < 0 || best > max_hamming) continue;
    if (ratio < 1.0 && best_level == second_level && best > ratio * second) continue;
    const auto k = static_cast<std::size_t>(best_index);
    if (best >= best_distance[k]) continue;
    best_distance[k] = best;
    owner[k] = static_cast<int>(c);
  }
  // Rotation consistency over the matches whose candidate's angle is known.
  std::vector<std::size_t> matched, rotated;
  std::vector<float> rotations;
  for (std::size_t k = 0; k < n; ++k) {
    if (owner[k] < 0) continue;
    matched.push_back(k);
    const ProjectedLandmark& cand = candidates[static_cast<std::size_t>(owner[k])];
    if (check_orientation && cand.angle >= 0.0F) {
      rotated.push_back(k);
      rotations.push_back(cand.angle - frame.keypoints[k].angle);
    }
  }
  std::vector<char> keep(n, 1);
  if (check_orientation) {
    const GuidedMatchOptions histogram;  // the features module's bins (ORB-SLAM's 30, 3 kept)
    const std::vector<char> consistent = rotation_consistent(rotations, histogram.histogram_bins, histogram.keep_bins);
    for (std::size_t i = 0; i < rotated.size(); ++i) keep[rotated[i]] = consistent[i];
  }
  int count = 0;
  if (candidate_of_keypoint != nullptr) candidate_of_keypoint->assign(n, -1);
  for (const std::size_t k : matched) {
    if (!keep[k]) continue;
    const ProjectedLandmark& cand = candidates[static_cast<std::size_t>(owner[k])];
    if (cand.id.valid()) frame.landmarks[k] = cand.id;
    if (candidate_of_keypoint != nullptr) (*candidate_of_keypoint)[k] = owner[k];
    frame.outlier[k] = false;
    ++count;
  }
  return count;
}

std::vector<std::pair<int, int>> match_brute_force(std::span<const Descriptor> query,
                                                   std::span<const Descriptor> train, int max_hamming,
                                                   double ratio) {
  BruteForceMatchOptions options;
  options.max_distance = max_hamming;
  options.ratio = 1.0F;  // the tracker's own test below: best <= ratio * second, in double
  std::vector<int> best_for_train(train.size(), INT_MAX);
  std::vector<int> query_for_train(train.size(), -1);
  for (const Match& m : rgbl::match_brute_force(query, train, options)) {  // ascending query
    if (m.distance > ratio * m.second_distance) continue;
    const auto t = static_cast<std::size_t>(m.train);
    if (m.distance < best_for_train[t]) {
      best_for_train[t] = m.distance;
      query_for_train[t] = m.query;
    }
  }
  std::vector<std::pair<int, int>> matches;
  for (std::size_t t = 0; t < train.size(); ++t) {
    if (query_for_train[t] >= 0) matches.emplace_back(query_for_train[t], static_cast<int>(t));
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

}  // namespace rgbl::detail
