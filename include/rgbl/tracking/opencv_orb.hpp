#pragma once
// Temporary adapter: OpenCV's ORB as a FeatureExtractor, until rgbl's own extractor is merged.

#include "rgbl/tracking/frame.hpp"

namespace rgbl {

struct OpenCvOrbOptions {
  int features = 2000;
  int levels = 8;
  float scale_factor = 1.2F;
  int fast_threshold = 12;
};

FeatureExtractor make_opencv_orb_extractor(const OpenCvOrbOptions& options = {});

}  // namespace rgbl
