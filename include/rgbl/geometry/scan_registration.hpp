#pragma once
// Registration of one LiDAR scan onto another from a pose guess: point-to-plane ICP with a robust
// (Cauchy) weight, and a check that the result is pinned down in every direction. Where the images
// cannot tell where the camera is (after a gap in the frames, a new map was started from the motion
// model's guess), two scans 30 m apart still share the road's shape, kerbs, poles and facades.
//
// ICP finds the nearest minimum, and on a road between two straight rows of trees or guard rails that
// minimum slides along the road: every along-track shift fits the road and the rails equally. Such a
// result is not a measurement. So the result is probed: moved by probe_shift_m along each axis, it
// must lose at least min_probe_loss of the points that land on the reference. A true registration is
// a peak (sequence 04's scans 32 m apart: 29 % lost at the weakest axis); a slide is a ridge (the
// same road from 35 m off: nothing lost). Both in test_geometry "scan registration*".

#include "rgbl/geometry/point_cloud.hpp"
#include "rgbl/geometry/scan_agreement.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <vector>

namespace rgbl {

class TaskPool;

struct ScanRegistrationOptions {
  double min_range = 3.0;         // m: nearer returns are the car itself
  double max_range = 60.0;        // m: two scans 30 m apart overlap out here
  double reference_voxel = 0.5;   // m: the reference keeps one point (the mean) per voxel of this edge
  double query_voxel = 1.0;       // m: the query, coarser (fewer, spread evenly over the scene)
  double normal_radius = 1.0;     // m: a reference point's plane is fitted to its neighbours within this
  int min_normal_points = 5;
  // Correspondences within coarse_distance for the first coarse_iterations (the guess may be a metre
  // or two off), then within fine_distance.
  double coarse_distance = 1.5;   // m
  int coarse_iterations = 5;
  double fine_distance = 0.5;     // m
  double robust_scale = 0.2;      // m: Cauchy weight 1 / (1 + (r / scale)^2) of a plane distance r
  int max_iterations = 50;
  double converged_m = 1e-3;      // an update below both ends the iterations
  double converged_deg = 0.01;
  std::size_t min_correspondences = 200;
  // The probe: points of the query (reference_voxel) agreeing within agreement_tolerance of a
  // reference point, at the result and moved by probe_shift_m along each axis of the reference.
  double agreement_tolerance = 0.3;  // m
  double probe_shift_m = 1.0;
  // A search over the heading for a guess that may be turned too far for ICP to recover (a gap in a
  // bend): ICP also starts from the guess turned about the query's vertical (z) axis by every multiple
  // of yaw_step_deg within +-yaw_range_deg, and of the converged results the one where most points
  // land wins. 0: the guess alone.
  double yaw_range_deg = 0.0;
  double yaw_step_deg = 5.0;
  // The same along the guess's direction of travel (its translation), for a guess too long or short
  // (a car braking in a gap): starts every along_step_m within +-along_range_m, each with every
  // heading above. 0: the guess's position alone.
  double along_range_m = 0.0;
  double along_step_m = 2.0;
  // The search runs ICP from every start on a coarser query (one point per search_voxel) for
  // search_iterations, ranks the results by the share of those points that land, and refines the
  // refine_best best that are distinct (more than probe_shift_m or half a yaw step apart) on the full
  // query; of those that converge, the one where most points land wins.
  double search_voxel = 2.0;  // m
  int search_iterations = 10;
  std::size_t refine_best = 3;

  void validate() const;
};

struct ScanRegistration {
  Eigen::Isometry3d T_reference_query = Eigen::Isometry3d::Identity();
  int iterations = 0;
  bool converged = false;           // the last update was below converged_m and converged_deg
  int starts = 1, converged_starts = 0;  // of the search; converged: of the refined ones
  // The best agreement among the other refined results that converged elsewhere (more than
  // probe_shift_m or half a yaw step from the winner): another optimum that fits about as well makes
  // the winner a coin toss.
  double runner_up_agreement = 0.0;
  std::size_t correspondences = 0;  // of the last iteration
  // Of the query's points at reference_voxel: the share landing on the reference at the result, and
  // the smallest share of those lost when the result is moved by probe_shift_m along an axis (0 when
  // some probe lands as well or better).
  double agreement = 0.0;
  double min_probe_loss = 0.0;
};

// Registers `query` (a scan in its own LiDAR frame) onto `reference` (another, in its own) from the
// guess T_reference_query (and the heading search's starts). Without a converged start, the guess's
// own run is returned with converged false. nullopt when there is not enough to register (fewer than
// min_correspondences correspondences, or a singular system, from every start). Throws ConfigError on
// bad options. With a pool, the search's starts and the refined seeds run on it; the result is the
// same with any pool or none.
std::optional<ScanRegistration> register_scans(PointCloudView reference, PointCloudView query,
                                               const Eigen::Isometry3d& T_reference_query_guess,
                                               const ScanRegistrationOptions& options = {}, TaskPool* pool = nullptr);

// One return per voxel of edge `voxel` (the mean of its returns, intensity 0), of the returns within
// options' min_range..max_range: what register_scans keeps of a reference at options.reference_voxel,
// so a scan stored this way registers as the full one would.
std::vector<LidarPoint> voxel_downsample(PointCloudView scan, const ScanRegistrationOptions& options, double voxel);

// A registration across a gap in the frames: from a constant-velocity guess over gap_s seconds,
// searched as far as that guess can be off, and taken only as a clear, pinned-down optimum within
// that reach. Used where the images alone cannot be trusted after a gap: the bridge between two maps
// (loop closing) and the tracker's first frame after a gap (docs/loop-closing.md, "Bridging a gap").
struct GapRegistrationOptions {
  // What the guess over a gap of t seconds can be off, and so the most the registration may move it:
  // allowance_m + max_acceleration t^2 / 2 and allowance_deg + max_turn_rate_deg_s t (a car braking
  // or accelerating at 4 m/s^2; turning at 25 deg/s, a junction turn of 10 m radius at 4.5 m/s).
  double allowance_m = 1.0;
  double max_acceleration = 4.0;  // m/s^2
  double allowance_deg = 2.0;
  double max_turn_rate_deg_s = 25.0;
  // The result must be a peak: moved 1 m along any axis it loses at least this share of the points
  // that land (scripts/jump-table.sh: 0.15-0.49 over its 28 bridges and the tracker's 44 accepted
  // registrations; 0.00-0.02 where ICP slides along a road it cannot place, e.g. sequence 04's jump
  // registered from 35 m short).
  double min_probe_loss = 0.1;
  // The search covers what the guess can be off (the bounds above, at most these), and its winner
  // must fit clearly better than any other optimum it found: the runner-up's share of landing points
  // at most this share of the winner's (the same table: 0-0.79 over those accepted; 0.82-0.99 where
  // houses or blocks repeat along the street, refused).
  double max_yaw_search_deg = 30.0;
  double max_along_search_m = 6.0;
  double max_runner_up_ratio = 0.8;
  ScanRegistrationOptions registration;

  double allowed_m(double gap_s) const { return allowance_m + 0.5 * max_acceleration * gap_s * gap_s; }
  double allowed_deg(double gap_s) const { return allowance_deg + max_turn_rate_deg_s * gap_s; }
  void validate() const;
};

struct GapRegistration {
  // The result between the two camera frames (register_across_gap's T_cam_lidar), and the
  // registration it comes from, between the LiDAR frames.
  Eigen::Isometry3d T_reference_query = Eigen::Isometry3d::Identity();
  ScanRegistration registration;
  double moved_m = 0.0, moved_deg = 0.0;  // how far the result is from the guess (the LiDAR's origin)
  double allowed_m = 0.0, allowed_deg = 0.0;
  bool accepted = false;  // converged, a clear peak, and within the allowance
};

// Registers `query` onto `reference` (scans in their own LiDAR frames, z up) across a gap of gap_s
// seconds from T_reference_query_guess, a motion between the camera frames T_cam_lidar maps the LiDAR
// into (both callers track cameras; identity: the LiDAR frames themselves). nullopt when there is too
// little to register. Throws ConfigError on bad options.
std::optional<GapRegistration> register_across_gap(PointCloudView reference, PointCloudView query,
                                                   const Eigen::Isometry3d& T_cam_lidar,
                                                   const Eigen::Isometry3d& T_reference_query_guess, double gap_s,
                                                   const GapRegistrationOptions& options = {},
                                                   TaskPool* pool = nullptr);

}  // namespace rgbl
