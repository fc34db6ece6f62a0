#include "rgbl/tracking/opencv_orb.hpp"

#include <opencv2/features2d.hpp>

#include <cstring>
#include <memory>

namespace rgbl {

FeatureExtractor make_opencv_orb_extractor(const OpenCvOrbOptions& options) {
  auto orb = cv::ORB::create(options.features, options.scale_factor, options.levels, 31, 0, 2,
                             cv::ORB::HARRIS_SCORE, 31, options.fast_threshold);
  return [orb](const cv::Mat& gray, std::vector<Keypoint>& keypoints, std::vector<Descriptor>& descriptors) {
    std::vector<cv::KeyPoint> cv_keypoints;
    cv::Mat cv_descriptors;
    orb->detectAndCompute(gray, cv::noArray(), cv_keypoints, cv_descriptors);
    keypoints.resize(cv_keypoints.size());
    descriptors.resize(cv_keypoints.size());
    for (std::size_t i = 0; i < cv_keypoints.size(); ++i) {
      const cv::KeyPoint& k = cv_keypoints[i];
      keypoints[i] = Keypoint{k.pt.x, k.pt.y, k.angle, k.response, k.size, k.octave};
      std::memcpy(descriptors[i].data(), cv_descriptors.ptr<std::uint8_t>(static_cast<int>(i)), 32);
    }
  };
}

}  // namespace rgbl
