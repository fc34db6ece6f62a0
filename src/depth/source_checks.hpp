#pragma once
// Input checks and conversions shared by the image-based depth sources (private to rgbl::depth).

#include "rgbl/core/error.hpp"
#include "rgbl/geometry/camera.hpp"

#include <fmt/format.h>
#include <opencv2/core/mat.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace rgbl::detail {

// Throws ConfigError(key) unless `image` has the camera's size.
inline void require_camera_size(const cv::Mat& image, const PinholeCamera& camera, const char* key) {
  if (image.cols != camera.width || image.rows != camera.height) {
    throw ConfigError(key, fmt::format("an image of the camera's size {}x{} (got {}x{})", camera.width,
                                       camera.height, image.cols, image.rows));
  }
}

inline void require_stereo_baseline(double baseline) {
  require(baseline > 0.0 && std::isfinite(baseline), "stereo_baseline", "the stereo baseline in metres (> 0)");
}

// The image itself when it is grey already, else its BGR -> grey conversion.
inline cv::Mat grey_image(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat out;
  cv::cvtColor(image, out, cv::COLOR_BGR2GRAY);
  return out;
}

}  // namespace rgbl::detail
