#pragma once
// Private matching helpers of the tracker (guided search by projection, brute force).

#include "rgbl/features/types.hpp"
#include "rgbl/map/map.hpp"
#include "rgbl/tracking/frame.hpp"

#include <span>
#include <utility>
#include <vector>

namespace rgbl::detail {

struct ProjectedLandmark {
  LandmarkId id;
  Descriptor descriptor{};  // a copy: the map may change once the lock is released
  float x = 0.0F, y = 0.0F;
  float radius = 0.0F;
  int min_level = 0, max_level = -1;
  float angle = -1.0F;  // angle of the keypoint it was last seen as; < 0 = unknown
  float depth = 0.0F;   // predicted camera z; > 0 enables the depth gate
};

// Keypoints whose measured depth differs from a candidate's predicted depth by more than
// max(min_gap, sigmas * keypoint sigma) are not matched to it: this rejects points of objects that
// move with the camera and aliasing on periodic structures.
struct DepthGate {
  float sigmas = 0.0F;   // 0 = off
  float min_gap = 0.0F;  // m
};

// Assigns frame.landmarks for the best keypoint of each candidate (only keypoints without a landmark).
// ratio < 1 applies the best/second-best test when both come from the same level.
// Candidates with an invalid id (temporary points) are reported only through candidate_of_keypoint
// (when given: candidate index per keypoint, -1 for none).
int match_projected(Frame& frame, std::span<const ProjectedLandmark> candidates, int max_hamming, double ratio,
                    bool check_orientation, std::vector<int>* candidate_of_keypoint = nullptr,
                    DepthGate gate = {});

// query index -> train index: features' brute-force nearest neighbour with the tracker's ratio test
// (best <= ratio * second best) and each train descriptor kept by its nearest query (ties: the lower).
std::vector<std::pair<int, int>> match_brute_force(std::span<const Descriptor> query,
                                                   std::span<const Descriptor> train, int max_hamming,
                                                   double ratio);

}  // namespace rgbl::detail
