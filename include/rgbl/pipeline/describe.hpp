#pragma once
// What `rgbl info` prints about a dataset folder: what the loader sees in it.

#include "rgbl/io/sequence.hpp"

#include <string>

namespace rgbl {

// The sequence for people: layout, name, frames and rate, each camera's size, intrinsics and offset
// from cam0, the LiDAR's points in frame 0 and its mounting, the depth camera, the ground truth's
// poses and path length, and the loader's notes. Reads frame 0's scan when there is a LiDAR (throws
// ParseError naming the file when it does not load).
std::string describe_sequence(const Sequence& sequence);

}  // namespace rgbl
