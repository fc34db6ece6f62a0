#include "rgbl/depth/sources.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/io/image.hpp"
#include "source_checks.hpp"

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <charconv>
#include <system_error>
#include <cmath>
#include <limits>

namespace rgbl {

CompletionMethod parse_completion_method(std::string_view text, const char* key) {
  if (text == "dilation") return CompletionMethod::dilation;
  if (text == "ip_basic_fast") return CompletionMethod::ip_basic_fast;
  if (text == "ip_basic_multiscale") return CompletionMethod::ip_basic_multiscale;
  throw ConfigError(key, "one of: dilation, ip_basic_fast, ip_basic_multiscale");
}

void LidarSourceOptions::validate() const {
  projection.validate();
  dilation.validate();
  ip_basic.validate();
  require(max_kernel_size >= 1 && max_kernel_size <= 63 && max_kernel_size % 2 == 1, "lidar.max_kernel_size",
          "an odd size 1..63 (the growth never goes below dilation.size)");
  require(surface_tolerance >= 0.0F && surface_tolerance < 1.0F, "lidar.surface_tolerance", "a fraction in [0, 1)");
  require(surface_step_px >= 1 && surface_step_px <= 15, "lidar.surface_step_px", "1 .. 15 px");
  require(occlusion_window_deg >= 0.0 && occlusion_window_deg < 5.0, "lidar.occlusion_window_deg", "0 (off) .. 5 deg");
  require(occlusion_ratio > 1.0F, "lidar.occlusion_ratio", "> 1");
  require(surface_fit_window_deg >= 0.0 && surface_fit_window_deg < 5.0, "lidar.surface_fit_window_deg", "0 (off) .. 5 deg");
  SurfacePlaneFit fit;  // its checks of the two options, not a copy of them
  fit.max_tilt_deg = surface_fit_max_tilt_deg;
  fit.range_sigma = range_sigma;
  fit.validate();
}

void PrecomputedSourceOptions::validate() const {
  require(!folder.empty(), "precomputed.folder", "the folder holding the depth PNGs");
  require(!file_pattern.empty(), "precomputed.file_pattern", "a file name pattern such as {:06d}.png");
  require(ignore_top_fraction >= 0.0 && ignore_top_fraction < 1.0, "precomputed.ignore_top_fraction",
          "a fraction in [0, 1)");
  require(max_depth > 0.0F, "precomputed.max_depth", "a depth > 0 m");
}

void StereoSourceOptions::validate() const {
  require(num_disparities >= 16 && num_disparities % 16 == 0, "stereo.num_disparities", "a positive multiple of 16");
  require(block_size >= 1 && block_size % 2 == 1 && block_size <= 11, "stereo.block_size", "an odd size in [1, 11]");
  require(uniqueness_ratio >= 0 && uniqueness_ratio <= 100, "stereo.uniqueness_ratio", "a percentage in [0, 100]");
  require(speckle_window >= 0, "stereo.speckle_window", "a size >= 0");
  require(speckle_range >= 0, "stereo.speckle_range", "a disparity range >= 0");
  require(min_disparity_px > 0.0F, "stereo.min_disparity_px", "a disparity > 0 px");
  require(max_depth > 0.0F, "stereo.max_depth", "a depth > 0 m");
}

void RgbdSourceOptions::validate() const {
  require(scale > 0.0 && std::isfinite(scale), "rgbd.scale", "a positive factor (units per metre, e.g. 5000)");
  require(max_depth > 0.0F, "rgbd.max_depth", "a depth > 0 m");
}

cv::Mat_<float> read_depth_png(const std::filesystem::path& file) {
  const cv::Mat raw = read_image_file(file, ImageMode::grey_any_depth, "a depth PNG (uint16, depth x 256)");
  if (raw.type() != CV_16UC1) throw ParseError(file, 0, "a single-channel uint16 PNG (depth x 256)");
  cv::Mat_<float> depth;
  raw.convertTo(depth, CV_32F, 1.0 / 256.0);
  return depth;
}

void write_depth_png(const std::filesystem::path& file, const cv::Mat_<float>& depth) {
  // atomically: a reader (a run using --depth precomputed) never sees half a map
  write_png_file(file, encode_depth16(depth));
}

void sample_dense_depth(const cv::Mat_<float>& dense, const Kernel& kernel, std::span<const Eigen::Vector2f> pixels,
                        std::span<KeypointDepth> out) {
  CV_Assert(out.size() == pixels.size());
  const int radius = kernel.radius();
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    KeypointDepth& result = out[i];
    result = {};
    const Eigen::Vector2f& p = pixels[i];
    const float fx = std::floor(p.x() + 0.5F), fy = std::floor(p.y() + 0.5F);
    if (!(fx >= 0.0F && fy >= 0.0F && fx < static_cast<float>(dense.cols) && fy < static_cast<float>(dense.rows))) continue;
    const int x = static_cast<int>(fx), y = static_cast<int>(fy);
    const float z = dense(y, x);
    if (!(z > 0.0F)) continue;
    float lo = z, hi = z;
    for (int dy = -radius; dy <= radius; ++dy) {
      const int r = y + dy;
      if (r < 0 || r >= dense.rows) continue;
      const int h = kernel.half_width(dy);
      for (int c = std::max(0, x - h); c <= std::min(dense.cols - 1, x + h); ++c) {
        const float d = dense(r, c);
        if (d > 0.0F) {
          lo = std::min(lo, d);
          hi = std::max(hi, d);
        }
      }
    }
    result.z = z;
    result.sample_distance_px = (p - Eigen::Vector2f(fx, fy)).norm();
    result.spread = hi - lo;
  }
}

namespace {

// The kernel for LiDAR rings `spacing` px apart in the image (LidarSourceOptions::kernel_from_ring_spacing):
// the configured one up to 1.5 times its size, beyond that one reaching half the spacing, at most
// max_size (never below the configured size). Only beyond 1.5 times: the HDL-64's two blocks of lasers
// put its rings 4-6 px apart on KITTI, and a frame's median spacing there is 5 or 6 px (raw drive 0009:
// 15 of its 51 frames 6): the 5x5 diamond was made for all of that range.
int kernel_size_for_rings(double spacing, int configured, int max_size) {
  if (!(spacing > 1.5 * configured)) return configured;
  const int reach = static_cast<int>(spacing / 2.0);
  return std::clamp(2 * reach + 1, configured, std::max(configured, max_size));
}

// Distance from `p` to the nearest non-zero pixel centre of `sparse` within `radius`; radius + 1 if none.
float nearest_sample_distance(const cv::Mat_<float>& sparse, const Eigen::Vector2f& p, int radius) {
  const int x = static_cast<int>(std::floor(p.x() + 0.5F)), y = static_cast<int>(std::floor(p.y() + 0.5F));
  float best2 = std::numeric_limits<float>::max();
  for (int r = std::max(0, y - radius); r <= std::min(sparse.rows - 1, y + radius); ++r) {
    for (int c = std::max(0, x - radius); c <= std::min(sparse.cols - 1, x + radius); ++c) {
      if (!(sparse(r, c) > 0.0F)) continue;
      const float ex = static_cast<float>(c) - p.x(), ey = static_cast<float>(r) - p.y();
      best2 = std::min(best2, ex * ex + ey * ey);
    }
  }
  return best2 == std::numeric_limits<float>::max() ? static_cast<float>(radius + 1) : std::sqrt(best2);
}

class LidarDepthSource final : public DepthSource {
 public:
  LidarDepthSource(const LidarSourceOptions& options, const DepthSourceContext& context)
      : camera_(context.calibration.camera),
        T_cam_lidar_(context.calibration.T_cam_lidar),
        P_img_lidar_(context.calibration.P_img_lidar()),
        options_(options) {
    options_.validate();
    occlusion_radius_ = occlusion_radius_px(camera_.fx, options_.occlusion_window_deg);  // 0: off
    surface_fit_ = {occlusion_radius_px(camera_.fy, options_.surface_fit_window_deg),  // 0: off
                    camera_, options_.surface_fit_max_tilt_deg, options_.range_sigma};
  }

  std::string_view name() const override { return "lidar"; }
  bool measured_at_scan_time() const override { return true; }

  void prepare(const SensorFrame& frame) override {
    // An empty scan is a LiDAR dropout, not a misconfiguration (a dataset without scans is refused
    // where the source is chosen): the projection leaves the frame without depth, and the tracker
    // copes with that.
    sparse_.create(camera_.height, camera_.width);
    Matrix34d P = P_img_lidar_;
    if (frame.T_image_scan.matrix() != Eigen::Matrix4d::Identity()) {
      // the scan's points first moved to where they are seen from at the image's time
      const Eigen::Isometry3d T_lidar_motion = T_cam_lidar_.inverse() * frame.T_image_scan * T_cam_lidar_;
      P = P_img_lidar_ * T_lidar_motion.matrix();
    }
    project_to_depth(frame.scan, P, options_.projection, sparse_);
    remove_occluded_samples(sparse_, occlusion_radius_, options_.occlusion_ratio, occlusion_scratch_);
    dilation_ = options_.dilation;
    fit_ = surface_fit_;
    const auto spacing = options_.kernel_from_ring_spacing && options_.completion == CompletionMethod::dilation
                             ? ring_spacing_px(sparse_)
                             : std::nullopt;
    if (spacing && *spacing > options_.dilation.size) {
      dilation_.size = kernel_size_for_rings(*spacing, options_.dilation.size, options_.max_kernel_size);
      // the road's plane fit between the rings above and below a keypoint needs both in its window
      if (dilation_.size != options_.dilation.size && fit_.rows > 0) {
        fit_.rows = std::max(fit_.rows, static_cast<int>(std::ceil(*spacing)));
      }
      logger()->debug("frame {}: LiDAR rings {} px apart in the image, dilation kernel {} (configured {})", frame.index,
                      *spacing, dilation_.size, options_.dilation.size);
    }
    dense_.release();
    if (options_.completion != CompletionMethod::dilation) dense_ = complete();
  }

  void sample(std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out) const override {
    if (options_.completion == CompletionMethod::dilation) {
      if (options_.keypoint_depth == KeypointDepthRule::surface_mean) {
        lookup_surface_depth(sparse_, dilation_, options_.surface_tolerance, pixels, out, fit_, options_.surface_step_px);
      } else {
        lookup_depth(sparse_, dilation_, pixels, out);
      }
      return;
    }
    sample_dense_depth(dense_, options_.dilation.kernel(), pixels, out);
    // IP-Basic fills from up to 15 px away: report the distance to the nearest real sample instead.
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      if (out[i].z > 0.0F) out[i].sample_distance_px = nearest_sample_distance(sparse_, pixels[i], 15);
    }
  }

  cv::Mat_<float> dense_depth() const override {
    if (options_.completion == CompletionMethod::dilation) return complete();
    return dense_.clone();
  }

 private:
  cv::Mat_<float> complete() const {
    switch (options_.completion) {
      case CompletionMethod::dilation: return dilate_depth(sparse_, dilation_);
      case CompletionMethod::ip_basic_fast: return ip_basic_fast(sparse_, options_.ip_basic);
      case CompletionMethod::ip_basic_multiscale: return ip_basic_multiscale(sparse_, options_.ip_basic);
    }
    return {};
  }

  PinholeCamera camera_;
  Eigen::Isometry3d T_cam_lidar_;
  Matrix34d P_img_lidar_;
  LidarSourceOptions options_;
  cv::Mat_<float> sparse_;
  DilationOptions dilation_;  // this frame's: options_.dilation, grown with the ring spacing
  SurfacePlaneFit fit_;       // this frame's: surface_fit_, its window grown with the ring spacing
  int occlusion_radius_ = 0;  // px, from occlusion_window_deg once
  SurfacePlaneFit surface_fit_;  // from surface_fit_window_deg and the camera, once
  cv::Mat_<float> occlusion_scratch_;
  cv::Mat_<float> dense_;  // only for the dense completion methods
};

// Shared by the sources that produce a dense map per frame in prepare().
class DenseDepthSource : public DepthSource {
 public:
  void sample(std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out) const override {
    sample_dense_depth(depth_, Kernel::diamond(5), pixels, out);
  }
  cv::Mat_<float> dense_depth() const override { return depth_.clone(); }

 protected:
  cv::Mat_<float> depth_;
};

class PrecomputedDepthSource final : public DenseDepthSource {
 public:
  PrecomputedDepthSource(const PrecomputedSourceOptions& options, const DepthSourceContext& context)
      : camera_(context.calibration.camera), options_(options) {
    options_.validate();
  }

  std::string_view name() const override { return "precomputed"; }

  void prepare(const SensorFrame& frame) override {
    const auto file = options_.folder / fmt::format(fmt::runtime(options_.file_pattern), frame.index);
    depth_ = read_depth_png(file);
    if (depth_.cols != camera_.width || depth_.rows != camera_.height) {
      throw ParseError(file, 0, fmt::format("a depth PNG of the camera's size {}x{} (got {}x{})", camera_.width,
                                            camera_.height, depth_.cols, depth_.rows));
    }
    const int ignored = static_cast<int>(std::lround(options_.ignore_top_fraction * depth_.rows));
    depth_.rowRange(0, ignored).setTo(0.0F);
    depth_.setTo(0.0F, depth_ > options_.max_depth);
  }

 private:
  PinholeCamera camera_;
  PrecomputedSourceOptions options_;
};

class StereoDepthSource final : public DenseDepthSource {
 public:
  StereoDepthSource(const StereoSourceOptions& options, const DepthSourceContext& context)
      : camera_(context.calibration.camera), baseline_(context.stereo_baseline), options_(options) {
    options_.validate();
    detail::require_stereo_baseline(baseline_);
    if (camera_.width > 0) require_width(camera_.width);
    const int area = options_.block_size * options_.block_size;
    matcher_ = cv::StereoSGBM::create(0, options_.num_disparities, options_.block_size, 8 * area, 32 * area, 1,
                                      0, options_.uniqueness_ratio, options_.speckle_window, options_.speckle_range,
                                      cv::StereoSGBM::MODE_SGBM_3WAY);
  }

  std::string_view name() const override { return "stereo"; }

  void prepare(const SensorFrame& frame) override {
    if (frame.image.empty() || frame.image_right.empty()) {
      throw ConfigError("frame.image_right", "a rectified stereo pair (image and image_right) for the stereo source");
    }
    detail::require_camera_size(frame.image, camera_, "frame.image");
    detail::require_camera_size(frame.image_right, camera_, "frame.image_right");
    require_width(frame.image.cols);
    matcher_->compute(detail::grey_image(frame.image), detail::grey_image(frame.image_right), disparity_);
    depth_.create(disparity_.rows, disparity_.cols);
    const float fb = static_cast<float>(camera_.fx * baseline_);
    for (int y = 0; y < disparity_.rows; ++y) {
      const auto* disparity = disparity_.ptr<std::int16_t>(y);
      float* out = depth_[y];
      for (int x = 0; x < disparity_.cols; ++x) {
        const float d = static_cast<float>(disparity[x]) * (1.0F / 16.0F);  // SGBM: 4 fractional bits
        const float z = d >= options_.min_disparity_px ? fb / d : 0.0F;
        out[x] = z <= options_.max_depth ? z : 0.0F;
      }
    }
  }

 private:
  // SGBM searches num_disparities columns to the left of each pixel: narrower images fail inside OpenCV
  // (an assertion, or an abort while it cleans up).
  void require_width(int width) const {
    if (width <= options_.num_disparities) {
      throw ConfigError("--depth", fmt::format("stereo on images wider than its disparity range "
                                               "(stereo.num_disparities = {} px), found images {} px wide; use "
                                               "stereo_sparse or lidar",
                                               options_.num_disparities, width));
    }
  }

  PinholeCamera camera_;
  double baseline_;
  StereoSourceOptions options_;
  cv::Ptr<cv::StereoSGBM> matcher_;
  cv::Mat disparity_;
};

class RgbdDepthSource final : public DenseDepthSource {
 public:
  RgbdDepthSource(const RgbdSourceOptions& options, const DepthSourceContext& context)
      : camera_(context.calibration.camera), options_(options) {
    options_.validate();
  }

  std::string_view name() const override { return "rgbd"; }

  void prepare(const SensorFrame& frame) override {
    if (frame.depth_image.empty()) throw ConfigError("frame.depth_image", "a depth image for the rgbd source");
    detail::require_camera_size(frame.depth_image, camera_, "frame.depth_image");
    if (frame.depth_image.type() == CV_16UC1) {
      frame.depth_image.convertTo(depth_, CV_32F, 1.0 / options_.scale);
    } else if (frame.depth_image.type() == CV_32FC1) {
      frame.depth_image.copyTo(depth_);
    } else {
      throw ConfigError("frame.depth_image", "a CV_16UC1 (scaled) or CV_32FC1 (metres) depth image");
    }
    // NaN (no return in some float formats) and out-of-range values become "no depth"
    for (int y = 0; y < depth_.rows; ++y) {
      float* row = depth_[y];
      for (int x = 0; x < depth_.cols; ++x) row[x] = (row[x] > 0.0F && row[x] <= options_.max_depth) ? row[x] : 0.0F;
    }
  }

 private:
  PinholeCamera camera_;
  RgbdSourceOptions options_;
};

}  // namespace

std::unique_ptr<DepthSource> make_lidar_source(const LidarSourceOptions& options, const DepthSourceContext& context) {
  return std::make_unique<LidarDepthSource>(options, context);
}
std::unique_ptr<DepthSource> make_precomputed_source(const PrecomputedSourceOptions& options,
                                                     const DepthSourceContext& context) {
  return std::make_unique<PrecomputedDepthSource>(options, context);
}
std::unique_ptr<DepthSource> make_stereo_source(const StereoSourceOptions& options, const DepthSourceContext& context) {
  return std::make_unique<StereoDepthSource>(options, context);
}
std::unique_ptr<DepthSource> make_rgbd_source(const RgbdSourceOptions& options, const DepthSourceContext& context) {
  return std::make_unique<RgbdDepthSource>(options, context);
}

void apply_lidar_argument(std::string_view argument, LidarSourceOptions& options) {
  const std::string arg(argument);
  if (arg.empty() || arg == "dilation") return;
  if (arg == "dilated") {
    options.keypoint_depth = KeypointDepthRule::dilated;  // the paper's keypoint depth: the dense map's value
  } else if (arg == "ipbasic" || arg == "ipbasic-fast") {
    options.completion = CompletionMethod::ip_basic_fast;
  } else if (arg == "ipbasic-multiscale") {
    options.completion = CompletionMethod::ip_basic_multiscale;
  } else {
    // <shape><size>, e.g. diamond5, rectangle3, cross7
    const auto digit = arg.find_first_of("0123456789");
    if (digit == std::string::npos || digit == 0) {
      throw ConfigError("--depth", fmt::format("lidar, lidar:dilated, lidar:ipbasic, lidar:ipbasic-multiscale or "
                                               "lidar:<diamond|rectangle|cross><size>, not 'lidar:{}'",
                                               arg));
    }
    try {
      options.dilation.shape = parse_kernel_shape(arg.substr(0, digit), "--depth");
    } catch (const ConfigError&) {
      throw ConfigError("--depth", fmt::format("a kernel shape diamond, rectangle or cross (e.g. lidar:diamond5), "
                                               "not 'lidar:{}'", arg));
    }
    // std::stoi would accept "7x" and throw a bare "stoi" on overflow: parse the whole tail.
    const std::string size = arg.substr(digit);
    int value = 0;
    const auto [end, ec] = std::from_chars(size.data(), size.data() + size.size(), value);
    if (ec != std::errc() || end != size.data() + size.size() || value < 1 || value > 63 || value % 2 == 0) {
      throw ConfigError("--depth", fmt::format("an odd kernel size 1..63 after the shape (e.g. lidar:diamond5), "
                                               "not 'lidar:{}'", arg));
    }
    options.dilation.size = value;
  }
}

namespace {

// An entry for a source that takes no argument, made by `make` (one of the make_*_source above).
template <typename Options>
DepthSourceEntry plain_entry(const char* name, DepthSourceNeeds needs, Options options,
                             std::unique_ptr<DepthSource> (*make)(const Options&, const DepthSourceContext&)) {
  return {needs, name, [name, options, make](std::string_view argument, const DepthSourceContext& context) {
            if (!argument.empty()) throw ConfigError("--depth", fmt::format("'{}' without an argument", name));
            return make(options, context);
          }};
}

}  // namespace

DepthSourceEntry lidar_depth_source(LidarSourceOptions options) {
  return {{.scan = true}, "lidar[:dilated|ipbasic|ipbasic-multiscale|<diamond|rectangle|cross><size>]",
          [options](std::string_view argument, const DepthSourceContext& context) {
            LidarSourceOptions o = options;
            apply_lidar_argument(argument, o);
            return make_lidar_source(o, context);
          }};
}

DepthSourceEntry precomputed_depth_source(PrecomputedSourceOptions options) {
  return {{}, "precomputed:<folder of uint16 depth PNGs>",
          [options](std::string_view argument, const DepthSourceContext& context) {
            PrecomputedSourceOptions o = options;
            if (!argument.empty()) o.folder = std::string(argument);
            if (o.folder.empty()) throw ConfigError("--depth", "precomputed:<folder of uint16 depth PNGs>");
            return make_precomputed_source(o, context);
          }};
}

DepthSourceEntry stereo_depth_source(StereoSourceOptions options) {
  return plain_entry("stereo", {.right_image = true}, options, &make_stereo_source);
}

DepthSourceEntry stereo_sparse_depth_source(StereoSparseSourceOptions options) {
  return plain_entry("stereo_sparse", {.right_image = true}, options, &make_stereo_sparse_source);
}

DepthSourceEntry rgbd_depth_source(RgbdSourceOptions options) {
  return plain_entry("rgbd", {.depth_image = true}, options, &make_rgbd_source);
}

DepthSourceRegistry builtin_depth_sources() {
  DepthSourceRegistry registry;
  registry.add("lidar", lidar_depth_source());
  registry.add("precomputed", precomputed_depth_source());
  registry.add("stereo", stereo_depth_source());
  registry.add("stereo_sparse", stereo_sparse_depth_source());
  registry.add("rgbd", rgbd_depth_source());
  return registry;
}

}  // namespace rgbl
