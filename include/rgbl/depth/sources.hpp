#pragma once
// The built-in depth sources and the settings they are created from. Each source turns one frame's
// sensor data into depth at keypoints (with the distance to the real measurement and the local depth
// spread) and into a dense map on demand. Create them directly or by name through a DepthSourceRegistry.

#include "rgbl/depth/completion.hpp"
#include "rgbl/depth/depth_source.hpp"
#include "rgbl/depth/ip_basic.hpp"
#include "rgbl/depth/registry.hpp"
#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/projection.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace rgbl {

enum class CompletionMethod { dilation, ip_basic_fast, ip_basic_multiscale };

// Parses "dilation" / "ip_basic_fast" / "ip_basic_multiscale"; throws ConfigError(key) otherwise.
CompletionMethod parse_completion_method(std::string_view text, const char* key = "lidar.completion");

// Depth at a keypoint with dilation: the mean of the winning surface (lookup_surface_depth, the
// default), or the dense map's value exactly (the paper's), whose minimum leans towards the camera
// wherever the kernel spans a depth gradient. On KITTI (1241 px wide) 96 % of the 5x5 kernels at
// keypoints hold a single LiDAR row and the bias is small; with more LiDAR rows per pixel (a smaller
// image, a LiDAR with more rows; the simulator's 613 px images) it grows: ~0.5 % there (docs/depth.md).
enum class KeypointDepthRule { dilated, surface_mean };

// `lidar`: the scan projected into the tracked camera (z-buffer), completed by inverse dilation (the
// paper's 5x5 diamond by default) or by IP-Basic. With dilation, sample() reads keypoints straight
// from the sparse image (no dense map).
struct LidarSourceOptions {
  ProjectionOptions projection{};
  CompletionMethod completion = CompletionMethod::dilation;
  DilationOptions dilation{};
  // With dilation, each frame's kernel grows to reach half the LiDAR's ring spacing in the image
  // (ring_spacing_px, measured on the frame's own scan) where that spacing is over 1.5 times the
  // configured size, so that a keypoint between two rings still finds one; never larger than
  // max_kernel_size; the road's plane fit (surface_fit_window_deg) then looks at least one spacing up
  // and down, to the rings either side. The paper's 5x5 diamond reaches half of KITTI's HDL-64 ring
  // spacing (4-6 px), which this leaves as it is; with every second ring (a 32-ring LiDAR) the kernel is
  // 11, with every fourth (16 rings) 19-23. On KITTI 04 and raw drive 0009 thinned so (mean ATE over
  // five samples) the 5x5 diamond's 0.107 / 0.103 m at 32 rings and 1.46 / 0.77 m at 16 (frames lost)
  // become 0.051 / 0.090 and 0.048 / 0.116 m; at 64 rings they are 0.063 / 0.090 m (docs/accuracy.md,
  // "Sparser LiDARs").
  bool kernel_from_ring_spacing = true;
  int max_kernel_size = 31;
  IpBasicOptions ip_basic{};
  KeypointDepthRule keypoint_depth = KeypointDepthRule::surface_mean;
  float surface_tolerance = 0.05F;  // relative depth step between neighbouring samples of one surface
  // The columns a step between two samples of one surface may span (lookup_surface_depth; rows: 2). On
  // a grown kernel a ring whose samples lie 3 px apart in one image row breaks the surface at 2, and the
  // keypoint gets the depth of the ring's end nearest the camera: the simulator at 1226 px with 16 rings
  // tracks at 0.086 m with 2 and 0.015 m with 4 (64 rings: 0.018 m). Not the default: KITTI's drives
  // thinned to 32 and 16 rings track worse with 4 in three of four (docs/accuracy.md, "A ring's samples
  // 3 px apart").
  int surface_step_px = 2;
  // Samples behind a foreground edge in the camera's view are dropped before completion
  // (remove_occluded_samples): those with a sample nearer by occlusion_ratio within occlusion_window_deg
  // (as an angle, so the same at any resolution: 4 px on KITTI's 1241 px images). A road changes its
  // depth by less than that across the window up to ~70 m away. 0 turns the filter off.
  double occlusion_window_deg = 0.3;
  float occlusion_ratio = 1.25F;
  // The surface-mean depth from a plane through the surface's samples within this angle above and below
  // the keypoint (lookup_surface_depth's SurfacePlaneFit; KITTI 6 px, the simulator 3 px at 0.5 deg), so
  // that a keypoint between two LiDAR rings on the road gets its own depth and not the nearer ring's;
  // only on surfaces about level below the camera whose samples lie on the plane. 0.5 deg is about one
  // HDL-64 ring spacing either side; 0 = off. On by default since 2026-12-05 (session 4), with the depth
  // noise's registration term (DepthNoiseModel::registration_sigma_deg, used only where this fit gives a
  // gradient): alone, the exact road depth made 04 follow its LiDAR-camera pitch (0.071 -> 0.090 m); with
  // the term, over five samples of the accuracy suite, the stress scenarios 0.91x and 04 0.063 m
  // (docs/accuracy.md, "The ring plane fit on by default").
  double surface_fit_window_deg = 0.5;
  // The fit only where the fitted plane is within this of level in the camera's frame (SurfacePlaneFit):
  // the tilt the tracker's ground model allows (TrackerOptions::ground_max_tilt_deg).
  double surface_fit_max_tilt_deg = 20.0;
  double range_sigma = 0.02;  // the scanner's range noise, m (the HDL-64E's datasheet: < 2 cm); the fit's residual test

  void validate() const;
};

// `precomputed`: one uint16 PNG per frame (depth x 256, 0 = none), e.g. a network's output.
struct PrecomputedSourceOptions {
  std::filesystem::path folder;
  std::string file_pattern = "{:06d}.png";  // fmt pattern of the frame index
  double ignore_top_fraction = 0.3;         // paper: the upper 30% of network depth is unreliable
  float max_depth = 80.0F;                  // depths beyond are dropped (KITTI depth GT ends at ~80 m)

  void validate() const;
};

// `stereo`: OpenCV semi-global block matching on the rectified pair, depth = fx * baseline / disparity.
struct StereoSourceOptions {
  int num_disparities = 128;  // multiple of 16
  int block_size = 5;         // odd
  int uniqueness_ratio = 10;  // percent
  int speckle_window = 100;
  int speckle_range = 2;
  float min_disparity_px = 1.0F;  // disparities below are dropped (depth too far to trust)
  float max_depth = 80.0F;

  void validate() const;
};

// `stereo_sparse`: depth at keypoints only, as ORB-SLAM's stereo frontend does it: for each left
// keypoint, a SAD patch search along the same row of the rectified right image (coarse on the half-
// resolution level, then +-3 px at full resolution), a uniqueness test, a parabola fit on the SAD costs
// for sub-pixel disparity, z = fx * baseline / disparity. No dense map is computed per frame.
struct StereoSparseSourceOptions {
  int max_disparity = 128;         // px at full resolution; search [0, max_disparity]: z >= fx * b / 128
  int window = 11;                 // odd SAD window at full resolution (ORB-SLAM: 11)
  int coarse_window = 7;           // odd SAD window on the half-resolution level
  int uniqueness_ratio = 10;       // percent the best coarse cost must beat the best outside +-1 disparity
  // The right patch searched back along the left row must agree (+-1 coarse px). Off by default: on
  // seq 04 it drops ~1.4 % of the depths, ATE 0.258 -> 0.255 m, for +1.3 ms per 2000 keypoints.
  bool left_right_check = false;
  float min_texture = 3.0F;        // mean |horizontal gradient| over the window, grey levels; below: no depth
  float max_mean_sad = 20.0F;      // mean |left - right| per pixel at the best match, grey levels
  float min_disparity_px = 1.0F;   // disparities below are dropped (depth too far to trust)
  float max_depth = 80.0F;         // m
  // Disparity uncertainty, reported as spread = z(d - s) - z(d + s): ~2 s z^2 / (fx b), so the depth
  // noise model's edge test drops far points (like ORB-SLAM's close/far threshold).
  float disparity_sigma_px = 0.5F;
  int dense_step = 4;              // dense_depth(): matched on this pixel grid only (visualisation)

  void validate() const;
};

// `rgbd`: a depth camera's image, CV_16UC1 divided by `scale` (TUM: 5000, most others 1000) or
// CV_32FC1 already in metres.
struct RgbdSourceOptions {
  double scale = 5000.0;
  float max_depth = 10.0F;

  void validate() const;
};

// The built-ins, created directly (the options are validated, naming their key).
std::unique_ptr<DepthSource> make_lidar_source(const LidarSourceOptions& options, const DepthSourceContext& context);
std::unique_ptr<DepthSource> make_precomputed_source(const PrecomputedSourceOptions& options,
                                                     const DepthSourceContext& context);
std::unique_ptr<DepthSource> make_stereo_source(const StereoSourceOptions& options, const DepthSourceContext& context);
std::unique_ptr<DepthSource> make_stereo_sparse_source(const StereoSparseSourceOptions& options,
                                                       const DepthSourceContext& context);
std::unique_ptr<DepthSource> make_rgbd_source(const RgbdSourceOptions& options, const DepthSourceContext& context);

// The `lidar` argument on top of `options`: empty or "dilation" (as is), "dilated" (the paper's keypoint
// depth), "ipbasic", "ipbasic-multiscale", or <diamond|rectangle|cross><odd size 1..63>. Throws
// ConfigError("--depth").
void apply_lidar_argument(std::string_view argument, LidarSourceOptions& options);

// Registry entries of the built-ins, each starting from the given options (e.g. a settings file's):
// lidar[:argument] (needs scans), precomputed:<folder> (reads PNGs itself), stereo and stereo_sparse
// (need the right image), rgbd (needs depth images).
DepthSourceEntry lidar_depth_source(LidarSourceOptions options = {});
DepthSourceEntry precomputed_depth_source(PrecomputedSourceOptions options = {});
DepthSourceEntry stereo_depth_source(StereoSourceOptions options = {});
DepthSourceEntry stereo_sparse_depth_source(StereoSparseSourceOptions options = {});
DepthSourceEntry rgbd_depth_source(RgbdSourceOptions options = {});

// lidar, precomputed, stereo, stereo_sparse and rgbd with default options.
DepthSourceRegistry builtin_depth_sources();

// Reads a depth PNG (uint16, depth x 256) into metres. Throws ParseError naming the file.
cv::Mat_<float> read_depth_png(const std::filesystem::path& file);
// Writes metres as uint16 PNG (encode_depth16 of rgbl/io/image.hpp: depth x 256, 0 = none, also for
// depths beyond 255.996 m), atomically. Throws Error naming the file on failure.
void write_depth_png(const std::filesystem::path& file, const cv::Mat_<float>& depth);

// Depth at keypoints read from a dense map: z at the nearest pixel centre, sample_distance_px the
// distance to that centre, spread over `kernel` around it. Used by the sources without a sparse input.
void sample_dense_depth(const cv::Mat_<float>& dense, const Kernel& kernel, std::span<const Eigen::Vector2f> pixels,
                        std::span<KeypointDepth> out);

}  // namespace rgbl
