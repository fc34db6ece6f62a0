#pragma once
// The simulator as a Sequence: frames rendered when loaded, never written to disk, so a drive of
// thousands of frames (scripts/longrun.sh) runs through the same Pipeline as a dataset folder.

#include "rgbl/io/sequence.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <memory>

namespace rgbl {

// KITTI-like (format kitti, name "synthetic"): the cameras in options.cameras, the LiDAR, the exact
// depth image when options.render_depth, exact ground truth. Thread-safe loads (const rendering).
std::unique_ptr<Sequence> make_synthetic_sequence(const SyntheticOptions& options);

}  // namespace rgbl
