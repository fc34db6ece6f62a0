#pragma once
// Depth completion by inverse dilation (SPEC section 3): every pixel takes the nearest valid depth
// under a small kernel centred on it. One pass, no post-filter. Depth is camera z in metres, 0 = none.
//
// The result is bit-identical to the paper's OpenCV formulation (invert valid depths with M - d, grey
// dilation, invert back with M - v, zero what maps back to M): the same float operations are applied,
// so even the rounding of M - (M - d) matches. Depths must lie in (0, M); others count as empty.

#include "rgbl/depth/depth_source.hpp"
#include "rgbl/geometry/camera.hpp"

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rgbl {

enum class KernelShape { diamond, rectangle, cross };

// A symmetric kernel made of horizontal runs centred on column 0: row dy (in [-radius, radius]) covers
// columns [-half_width(dy), half_width(dy)]. Diamonds, full rectangles and crosses are all of this form.
class Kernel {
 public:
  // size is the odd side length (3, 5, 7, 9, ...). Throws ConfigError("kernel.size") otherwise.
  Kernel(KernelShape shape, int size);

  static Kernel diamond(int size) { return {KernelShape::diamond, size}; }
  static Kernel rectangle(int size) { return {KernelShape::rectangle, size}; }
  static Kernel cross(int size) { return {KernelShape::cross, size}; }

  KernelShape shape() const { return shape_; }
  int size() const { return 2 * radius_ + 1; }
  int radius() const { return radius_; }
  int half_width(int dy) const;
  int cell_count() const;
  // 0/1 CV_8U structuring element of size x size (for cv::dilate).
  cv::Mat structuring_element() const;
  // "diamond5", "rectangle3", "cross7"
  std::string name() const;

 private:
  KernelShape shape_;
  int radius_;
};

// Parses "diamond" / "rectangle" / "cross"; throws ConfigError(key) naming the choices otherwise.
KernelShape parse_kernel_shape(std::string_view text, const char* key = "kernel.shape");

// The LiDAR's ring spacing where its scan lands in the image, in pixels: the median vertical gap
// between consecutive samples (more than 1 px apart) in about 26 bands of 3 columns across the image (one
// every 48 columns on KITTI's 1226 px; closer on narrower images, never further apart).
// Every ring crosses a 3-column band; a single column would miss most rings (a ring's samples lie 3 px
// apart within an image row on KITTI, the median). KITTI's HDL-64: 5-6 px; every second ring 10-11, every
// fourth 19-22.
// std::nullopt with fewer than min_gaps gaps (an empty or nearly empty scan).
std::optional<double> ring_spacing_px(const cv::Mat_<float>& sparse, std::size_t min_gaps = 100);

struct DilationOptions {
  KernelShape shape = KernelShape::diamond;
  int size = 5;              // odd side length (paper: 5x5 diamond)
  float max_depth = 200.0F;  // M, the inversion constant: depths must be < M (paper: the max range)

  Kernel kernel() const { return {shape, size}; }
  void validate() const;  // keys dilation.size, dilation.max_depth
};

// Dense inverse dilation of `sparse` into `dense` (allocated to sparse's size if needed; may not alias).
void dilate_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, cv::Mat_<float>& dense);
cv::Mat_<float> dilate_depth(const cv::Mat_<float>& sparse, const DilationOptions& options = {});

// The completed depth at keypoint pixels without building the dense map: pixel (u, v) reads the cell
// at the nearest pixel centre, and its z equals dense(round(v), round(u)) exactly. Also gives the
// distance from (u, v) to the centre of the LiDAR sample that supplied z (the nearest one on ties) and
// the spread (max - min) of the valid depths under the kernel. Pixels outside the image get z = 0.
void lookup_depth(const cv::Mat_<float>& sparse, const DilationOptions& options,
                  std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out);
KeypointDepth lookup_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, const Eigen::Vector2f& pixel);

// The ring plane fit of lookup_surface_depth. A plane through the samples, 1/z = a + b du + c dv at
// pixel offsets (du, dv) from the keypoint (u, v), has in the camera's frame the normal
// (b fx, c fy, a - b (u - cx) - c (v - cy)); it is fitted only where that normal lies within
// max_tilt_deg of the camera's down axis (+y): a surface below the camera, level or sloping like a road.
// On a wall a ring runs along the surface and the mean already holds. Nor is it fitted where the
// samples scatter about the plane by more than pixel rounding and range_sigma explain (3 sigma): far
// away a depth step between two objects, which the surface's growth can cross, looks level.
struct SurfacePlaneFit {
  int rows = 0;          // px above and below the keypoint; 0 = off
  PinholeCamera camera;  // the image's intrinsics (needed when rows > 0)
  double max_tilt_deg = 20.0;
  // The samples must lie on the plane within their rounding to pixel centres and this range noise, m.
  double range_sigma = 0.02;

  void validate() const;
};

// The dilation's keypoint depth without its bias towards the camera. The same kernel and the same
// foreground rule (the nearest surface under the kernel wins), but z is the inverse-distance-weighted
// mean, in inverse depth, of the samples on that surface instead of the nearest depth itself: on every
// slanted surface the minimum comes from the side that faces the camera (on the road about
// z^2 / (fx h) per pixel of kernel), the mean does not. The surface grows from the nearest sample
// through samples within step_px columns and 2 rows whose depths differ by at most surface_tolerance
// (relative), so a road joins row by row and a background behind an edge stays out. Where a ring's
// samples lie further apart along it than step_px, the surface stops at the first such gap: on a
// grown kernel only the end that faces the camera is left (LidarSourceOptions::surface_step_px).
// Weights are 1 / max(distance, 0.5 px).
// sample_distance_px is the nearest surface sample's distance; spread is as for lookup_depth. Pixels
// outside the image get z = 0.
// fit.rows > 0: z comes instead from a plane fitted, in inverse depth (affine in the pixel on a plane),
// to the samples of that surface within fit.rows px above and below (and 2 px either side), evaluated
// at the keypoint, when they bracket its row and the plane is level within fit.max_tilt_deg in the
// camera's frame (the road, a ramp; see SurfacePlaneFit). A LiDAR's rings sit at fixed elevations from the car, so
// on the road a keypoint between two rings otherwise reads the nearer ring's depth, which moves with
// the car: between two frames its depth then changes by less than the car moved (docs/accuracy.md,
// "LiDAR rings move with the car"). The surface grows from the kernel's surface through steps of up to
// surface_tolerance per 2 rows; the fit is kept only within 3 x surface_tolerance of the mean.
void lookup_surface_depth(const cv::Mat_<float>& sparse, const DilationOptions& options, float surface_tolerance,
                          std::span<const Eigen::Vector2f> pixels, std::span<KeypointDepth> out,
                          const SurfacePlaneFit& fit = {}, int step_px = 2);

// Drops the samples of `sparse` that the camera cannot see: a sample with a sample nearer by more than
// the factor `ratio` within `radius` px (a square) lies behind a foreground edge in the camera's view.
// The LiDAR sees past such edges from where it sits (on KITTI 0.27 m behind and 0.08 m above the
// camera; a scan that is not motion-compensated adds its own shift), so background returns land a few
// pixels inside foreground objects, where keypoints concentrate (corners). Returns how many were dropped.
int remove_occluded_samples(cv::Mat_<float>& sparse, int radius, float ratio);
// The same with a caller-kept scratch image (no allocation per frame).
int remove_occluded_samples(cv::Mat_<float>& sparse, int radius, float ratio, cv::Mat_<float>& scratch);

// The half-width in px of a window of `window_deg` seen by a camera of focal length `fx` px (>= 1 for a
// positive angle, 0 for 0): the occlusion filter's window as an angle means the same at any resolution.
int occlusion_radius_px(double fx, double window_deg);

// Share of pixels with depth (> 0), in [0, 1].
double depth_density(const cv::Mat_<float>& depth);

}  // namespace rgbl
