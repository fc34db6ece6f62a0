#pragma once
// The explicit depth noise model that replaces ORB-SLAM's virtual baseline. A LiDAR-derived depth at
// a keypoint is trusted according to how far it is and how far the keypoint is from the real LiDAR
// sample the value was copied from (inverse dilation fills a 5x5 diamond around each sample); a
// keypoint whose kernel straddles a depth edge gets no depth at all, because inverse dilation hands it
// the nearer (foreground) depth, which is what biases the scale of the reference implementation.

namespace rgbl {

struct DepthNoiseModel {
  double sigma_min = 0.03;          // m; sensor noise of a LiDAR return
  double sigma_relative = 0.005;    // sigma grows by this fraction of z (calibration, sync)
  // Depth change per pixel moved on a surface seen at grazing angle is ~ z^2 / (f * h); this gain
  // times sample_distance_px * z^2 / fx is the added sigma for a value copied from a neighbour pixel.
  double sigma_per_pixel = 0.1;
  // Triangulation-like growth sigma = sigma_quadratic * z^2 (ORB-SLAM's virtual baseline bf gives
  // 1 / bf here), for errors that grow with z^2: LiDAR-camera calibration and sync, motion distortion.
  double sigma_quadratic = 0.0;
  // The scan's registration to the image is known to about this angle (LiDAR-camera calibration,
  // sync): a depth read where it changes by g metres per pixel is off by up to g times that many pixels.
  // Adds (registration_sigma_deg in px * gradient)^2, with the source's gradient (KeypointDepth; the
  // LiDAR source's ring plane fit gives it on the road; with the fit off, LiDAR.SurfaceFitWindowDeg 0,
  // nothing changes). 0.1 deg: both KITTI drives here track best with their scans turned 0.05-0.1 deg up
  // (calibrated on different days), and 04 tracks about equally well from 0.05 to 0.2 deg
  // (docs/accuracy.md, "Road depth weighted by its registration").
  double registration_sigma_deg = 0.1;
  double max_spread = 1.0;          // m; above max(max_spread, max_spread_relative * z): a depth edge
  double max_spread_relative = 0.05;
  double min_depth = 0.1, max_depth = 120.0;  // m; depths outside are not used
  double max_sigma_relative = 0.15; // depths with sigma above this fraction of z are dropped

  void validate() const;

  // Standard deviation of a keypoint depth in metres, or 0 when the depth should not be used.
  // gradient: the surface's depth change per pixel at the keypoint (m/px), 0 = unknown.
  double sigma(double z, double sample_distance_px, double spread, double fx, double gradient = 0.0) const;
};

}  // namespace rgbl
