#include "rgbl/geometry/scan_registration.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/geometry/voxel_index.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace rgbl {

void ScanRegistrationOptions::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  require(std::isfinite(min_range) && min_range >= 0.0, "scan_registration.min_range", ">= 0 m");
  require(std::isfinite(max_range) && max_range > min_range, "scan_registration.max_range", "finite and > min_range");
  require(positive(reference_voxel), "scan_registration.reference_voxel", "> 0 m");
  require(positive(query_voxel), "scan_registration.query_voxel", "> 0 m");
  require(positive(normal_radius), "scan_registration.normal_radius", "> 0 m");
  require(min_normal_points >= 3, "scan_registration.min_normal_points", ">= 3 points (a plane)");
  require(positive(coarse_distance), "scan_registration.coarse_distance", "> 0 m");
  require(coarse_iterations >= 0, "scan_registration.coarse_iterations", ">= 0");
  require(positive(fine_distance) && fine_distance <= coarse_distance, "scan_registration.fine_distance",
          "> 0 m and <= coarse_distance");
  require(positive(robust_scale), "scan_registration.robust_scale", "> 0 m");
  require(max_iterations >= 1, "scan_registration.max_iterations", ">= 1");
  require(positive(converged_m), "scan_registration.converged_m", "> 0 m");
  require(positive(converged_deg), "scan_registration.converged_deg", "> 0 deg");
  require(min_correspondences >= 6, "scan_registration.min_correspondences", ">= 6 (six unknowns)");
  require(positive(agreement_tolerance), "scan_registration.agreement_tolerance", "> 0 m");
  require(positive(probe_shift_m), "scan_registration.probe_shift_m", "> 0 m");
  require(std::isfinite(yaw_range_deg) && yaw_range_deg >= 0.0 && yaw_range_deg <= 180.0,
          "scan_registration.yaw_range_deg", "in [0, 180] deg");
  require(positive(yaw_step_deg), "scan_registration.yaw_step_deg", "> 0 deg");
  require(std::isfinite(along_range_m) && along_range_m >= 0.0 && along_range_m <= 100.0,
          "scan_registration.along_range_m", "in [0, 100] m");
  require(positive(along_step_m), "scan_registration.along_step_m", "> 0 m");
  require(positive(search_voxel), "scan_registration.search_voxel", "> 0 m");
  require(search_iterations >= 1, "scan_registration.search_iterations", ">= 1");
  require(refine_best >= 1, "scan_registration.refine_best", ">= 1");
}

namespace {

// One point per voxel of edge `voxel`: the mean of the voxel's returns within the range.
ScanSample voxel_sample(PointCloudView scan, const ScanRegistrationOptions& options, double voxel) {
  const auto min2 = static_cast<float>(options.min_range * options.min_range);
  const auto max2 = static_cast<float>(options.max_range * options.max_range);
  const auto inv = static_cast<float>(1.0 / voxel);
  VoxelIndex index;
  std::vector<Eigen::Vector3f> sums;
  std::vector<float> counts;
  for (const LidarPoint& l : scan) {
    const Eigen::Vector3f p(l.x, l.y, l.z);
    const float r2 = p.squaredNorm();
    if (!(r2 >= min2 && r2 <= max2)) continue;  // also drops NaN
    const auto [slot, added] = index.emplace(voxel_of(p, inv), static_cast<std::uint32_t>(sums.size()));
    if (added) {
      sums.emplace_back(Eigen::Vector3f::Zero());
      counts.push_back(0.0F);
    }
    sums[slot] += p;
    counts[slot] += 1.0F;
  }
  ScanSample sample;
  sample.points.reserve(sums.size());
  for (std::size_t i = 0; i < sums.size(); ++i) sample.points.push_back(sums[i] / counts[i]);
  return sample;
}

// How far an ICP query point may move before its neighbourhood is searched again: of 1/3, 2/3 and 3/2
// of fine_distance, 2/3 registered three of 04's keyframe pairs fastest on average (fewer searches
// against more points each).
double search_slack(const ScanRegistrationOptions& options) { return 2.0 / 3.0 * options.fine_distance; }

// Reference points with their planes, grouped by voxels for neighbour searches within their edge (the
// 3x3x3 block around a point holds them all): the plane's radius, or the coarse correspondence distance
// plus the slack, so that even the coarse iterations keep their neighbourhoods.
class PlaneGrid {
 public:
  PlaneGrid(const ScanSample& points, const ScanRegistrationOptions& options)
      : inv_(1.0F / static_cast<float>(
                        std::max(options.coarse_distance + search_slack(options), options.normal_radius))),
        grid_(points.points, inv_) {
    fit_planes(options);
  }

  // Appends the reference points with a plane within `radius` (at most edge()) of p, by voxel.
  void gather(const Eigen::Vector3f& p, float radius, std::vector<std::uint32_t>& out) const {
    constexpr float kFar = 1e5F;  // a pose gone wild: nothing near, and voxel keys stay in range
    if (!(p.cwiseAbs().maxCoeff() < kFar)) return;
    const float radius2 = radius * radius;
    const VoxelKey c = voxel_of(p, inv_);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const std::uint32_t slot = grid_.index.find({c.x + dx, c.y + dy, c.z + dz});
          if (slot == VoxelIndex::npos) continue;
          for (std::uint32_t j = grid_.begin[slot]; j < grid_.begin[slot + 1]; ++j) {
            if (has_plane_[j] && (grid_.points[j] - p).squaredNorm() <= radius2) out.push_back(j);
          }
        }
      }
    }
  }
  float edge() const { return 1.0F / inv_; }

  const Eigen::Vector3f& point(int j) const { return grid_.points[static_cast<std::size_t>(j)]; }
  const Eigen::Vector3f& normal(int j) const { return normals_[static_cast<std::size_t>(j)]; }

 private:
  // A point's plane: the least-squares plane of its neighbours within normal_radius (itself included).
  // Neighbourhood is symmetric, so each pair of points is measured once, voxel against voxel: a voxel,
  // then each of the 13 neighbours that follow it (the other 13 see it as theirs).
  void fit_planes(const ScanRegistrationOptions& options) {
    const auto radius2 = static_cast<float>(options.normal_radius * options.normal_radius);
    const std::size_t count = grid_.points.size();
    // per point: the sum of the offsets to its neighbours, and of their outer products (xx xy xz yy yz zz)
    std::vector<Eigen::Vector3f> sums(count, Eigen::Vector3f::Zero());
    std::vector<Eigen::Matrix<float, 6, 1>> outers(count, Eigen::Matrix<float, 6, 1>::Zero());
    std::vector<int> neighbours(count, 1);
    const auto pair = [&](std::uint32_t i, std::uint32_t j) {
      const Eigen::Vector3f d = grid_.points[j] - grid_.points[i];
      if (d.squaredNorm() > radius2) return;
      Eigen::Matrix<float, 6, 1> o;
      o << d.x() * d.x(), d.x() * d.y(), d.x() * d.z(), d.y() * d.y(), d.y() * d.z(), d.z() * d.z();
      sums[i] += d;
      sums[j] -= d;
      outers[i] += o;
      outers[j] += o;
      ++neighbours[i];
      ++neighbours[j];
    };
    const std::size_t voxels = grid_.begin.size() - 1;
    for (std::size_t slot = 0; slot < voxels; ++slot) {
      const std::uint32_t a0 = grid_.begin[slot], a1 = grid_.begin[slot + 1];
      for (std::uint32_t i = a0; i < a1; ++i) {
        for (std::uint32_t j = i + 1; j < a1; ++j) pair(i, j);
      }
      const VoxelKey c = voxel_of(grid_.points[a0], inv_);
      for (int dx = 0; dx <= 1; ++dx) {
        for (int dy = dx == 0 ? 0 : -1; dy <= 1; ++dy) {
          for (int dz = (dx == 0 && dy == 0) ? 1 : -1; dz <= 1; ++dz) {
            const std::uint32_t other = grid_.index.find({c.x + dx, c.y + dy, c.z + dz});
            if (other == VoxelIndex::npos) continue;
            for (std::uint32_t i = a0; i < a1; ++i) {
              for (std::uint32_t j = grid_.begin[other]; j < grid_.begin[other + 1]; ++j) pair(i, j);
            }
          }
        }
      }
    }
    normals_.assign(count, Eigen::Vector3f::Zero());
    has_plane_.assign(count, false);
    for (std::size_t i = 0; i < count; ++i) {
      if (neighbours[i] < options.min_normal_points) continue;
      const auto n = static_cast<float>(neighbours[i]);
      const Eigen::Vector3f mean = sums[i] / n;
      const Eigen::Matrix<float, 6, 1>& o = outers[i];
      Eigen::Matrix3f outer;
      outer << o[0], o[1], o[2], o[1], o[3], o[4], o[2], o[4], o[5];
      const Eigen::Matrix3f covariance = outer / n - mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(covariance);
      if (solver.info() != Eigen::Success) continue;
      normals_[i] = solver.eigenvectors().col(0);  // smallest eigenvalue first
      has_plane_[i] = normals_[i].allFinite();
    }
  }

  float inv_;
  VoxelBuckets grid_;  // the points, grouped by voxel; planes per point in that order
  std::vector<Eigen::Vector3f> normals_;
  std::vector<bool> has_plane_;
};

// The share of `sample`'s points that land on the reference under T (0 for an empty sample).
double share_of(std::size_t landing, const ScanSample& sample) {
  return sample.empty() ? 0.0 : static_cast<double>(landing) / static_cast<double>(sample.points.size());
}
double landing_share(const ScanAgreement& agreement, const ScanSample& sample, const Eigen::Isometry3d& T) {
  return share_of(agreement.count(sample, T), sample);
}

// One ICP run from `guess`: the pose, whether it converged, the last iteration's correspondences and
// the iterations taken.
struct IcpRun {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  bool converged = false;
  std::size_t correspondences = 0;
  int iterations = 0;
};

// nullopt when too few correspondences or a singular system. With keep_short, a run that falls short of
// min_correspondences after its first iteration returns where it got to, not converged (the search
// ranks such starts by their landing share).
std::optional<IcpRun> run_icp(const PlaneGrid& grid, const ScanSample& query, const Eigen::Isometry3d& guess,
                              const ScanRegistrationOptions& options, bool keep_short = false) {
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  const double converged_rad = options.converged_deg * std::numbers::pi / 180.0;
  const double scale2 = options.robust_scale * options.robust_scale;
  IcpRun run;
  run.T = guess;
  // A query point moves little from one iteration to the next, so each keeps the reference points
  // within `reach` of where it was last searched (its anchor) and, while it stays within reach -
  // max_distance of the anchor, searches those alone: they hold every point within max_distance of it.
  // The same nearest point as a search of the grid, found among a handful instead of a hundred.
  struct Neighbourhood {
    Eigen::Vector3f anchor = Eigen::Vector3f::Zero();
    float reach = -1.0F;  // none yet
    std::uint32_t begin = 0, end = 0;
  };
  std::vector<Neighbourhood> cache(query.points.size());
  std::vector<std::uint32_t> pool;  // the neighbourhoods' points
  const std::size_t pool_limit = 64 * query.points.size() + 1024;
  const auto slack = static_cast<float>(search_slack(options));
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const auto max_distance =
        static_cast<float>(iteration < options.coarse_iterations ? options.coarse_distance : options.fine_distance);
    const float reach = std::min(grid.edge(), max_distance + slack);  // the edge holds max_distance + slack
    const float max2 = max_distance * max_distance;
    if (pool.size() > pool_limit) {  // regathered often (a guess far off): start again
      pool.clear();
      for (Neighbourhood& hood : cache) hood.reach = -1.0F;
    }
    const Eigen::Isometry3f Tf = run.T.cast<float>();
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    std::size_t used = 0;
    // the point-to-plane residual of query point x (in the reference's frame) against reference point j
    const auto add = [&](const Eigen::Vector3f& x, int j) {
      const Eigen::Vector3d n = grid.normal(j).cast<double>();
      const Eigen::Vector3d xd = x.cast<double>();
      const double r = n.dot(xd - grid.point(j).cast<double>());
      // d(n . (exp(xi) x)) / d[rho; phi] at 0 = [n; x x n]
      Vector6d J;
      J << n, xd.cross(n);
      const double w = 1.0 / (1.0 + r * r / scale2);
      H.noalias() += w * J * J.transpose();
      g.noalias() += w * r * J;
      ++used;
    };
    for (std::size_t i = 0; i < query.points.size(); ++i) {
      const Eigen::Vector3f x = Tf * query.points[i];
      Neighbourhood& hood = cache[i];
      if (!((x - hood.anchor).norm() + max_distance <= hood.reach)) {
        hood.anchor = x;
        hood.reach = reach;
        hood.begin = static_cast<std::uint32_t>(pool.size());
        grid.gather(x, reach, pool);
        hood.end = static_cast<std::uint32_t>(pool.size());
      }
      int j = -1;
      float best2 = max2;
      for (std::uint32_t k = hood.begin; k < hood.end; ++k) {
        const float d2 = (grid.point(static_cast<int>(pool[k])) - x).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          j = static_cast<int>(pool[k]);
        }
      }
      if (j >= 0) add(x, j);
    }
    run.correspondences = used;
    run.iterations = iteration + 1;
    if (used < options.min_correspondences) {
      if (keep_short && iteration > 0) return run;
      return std::nullopt;
    }
    const Eigen::LDLT<Matrix6d> solver(H);
    if (solver.info() != Eigen::Success) return std::nullopt;
    const Vector6d xi = -solver.solve(g);
    if (!xi.allFinite()) return std::nullopt;
    run.T = se3_exp(xi) * run.T;
    if (xi.head<3>().norm() < options.converged_m && xi.tail<3>().norm() < converged_rad) {
      run.converged = true;
      break;
    }
  }
  return run;
}

}  // namespace

std::vector<LidarPoint> voxel_downsample(PointCloudView scan, const ScanRegistrationOptions& options, double voxel) {
  require(std::isfinite(voxel) && voxel > 0.0, "voxel_downsample.voxel", "> 0 m");
  const ScanSample sample = voxel_sample(scan, options, voxel);
  std::vector<LidarPoint> points;
  points.reserve(sample.points.size());
  for (const Eigen::Vector3f& p : sample.points) points.push_back({p.x(), p.y(), p.z(), 0.0F});
  return points;
}

std::optional<ScanRegistration> register_scans(PointCloudView reference, PointCloudView query,
                                               const Eigen::Isometry3d& T_reference_query_guess,
                                               const ScanRegistrationOptions& options, TaskPool* pool) {
  options.validate();
  const ScanSample reference_points = voxel_sample(reference, options, options.reference_voxel);
  const ScanSample query_points = voxel_sample(query, options, options.query_voxel);
  const PlaneGrid grid(reference_points, options);
  // the agreement is counted on the query at the reference's density
  const bool same_voxel = options.query_voxel == options.reference_voxel;
  const ScanSample finer = same_voxel ? ScanSample{} : voxel_sample(query, options, options.reference_voxel);
  const ScanSample& dense = same_voxel ? query_points : finer;
  const ScanAgreement agreement(reference_points, options.agreement_tolerance);

  // The starts: the guess moved along its own direction of travel by every multiple of along_step_m
  // within along_range_m (a car braking or speeding up in a gap), each turned about the query's
  // vertical axis by every multiple of yaw_step_deg within yaw_range_deg (a bend); nearest first.
  const auto offsets = [](double range, double step) {
    std::vector<double> out{0.0};
    for (double v = step; v <= range + 1e-9; v += step) {
      out.push_back(v);
      out.push_back(-v);
    }
    return out;
  };
  const std::vector<double> yaws = offsets(options.yaw_range_deg, options.yaw_step_deg);
  const std::vector<double> alongs = offsets(options.along_range_m, options.along_step_m);
  const Eigen::Vector3d travel = T_reference_query_guess.translation().norm() > 1e-6
                                     ? Eigen::Vector3d(T_reference_query_guess.translation().normalized())
                                     : Eigen::Vector3d::UnitX();
  const double apart_rad = 0.5 * options.yaw_step_deg * std::numbers::pi / 180.0;
  const auto distinct = [&](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    const Eigen::Isometry3d d = a.inverse() * b;
    return d.translation().norm() > options.probe_shift_m || rotation_angle(d.linear()) > apart_rad;
  };

  // With more than one start, a search first: ICP on a coarser query (search_voxel) for a few
  // iterations from each start, ranked by the share of those points that land; the refine_best
  // distinct best are refined below. Without a search, the guess is refined alone.
  std::vector<Eigen::Isometry3d> seeds;
  const std::size_t start_count = yaws.size() * alongs.size();
  if (start_count == 1) {
    seeds.push_back(T_reference_query_guess);
  } else {
    const ScanSample coarse = voxel_sample(query, options, options.search_voxel);
    ScanRegistrationOptions search = options;
    search.max_iterations = options.search_iterations;
    search.min_correspondences = std::max<std::size_t>(
        6, options.min_correspondences * coarse.points.size() / std::max<std::size_t>(1, query_points.points.size()));
    // each start's result in its own slot, gathered in the starts' order: the same with any pool
    std::vector<std::optional<std::pair<double, Eigen::Isometry3d>>> slots(start_count);
    parallel_for(pool, start_count, [&](std::size_t k) {
      const double along = alongs[k / yaws.size()], yaw = yaws[k % yaws.size()];
      Eigen::Isometry3d start =
          T_reference_query_guess *
          Eigen::Isometry3d(Eigen::AngleAxisd(yaw * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()));
      start.translation() += along * travel;
      // a start short of correspondences at the fine distance still ranks: where moving trucks fill the
      // scans, no start keeps enough of the coarse points within it (traffic seed 3 braking through a
      // 1.1 s gap), yet the one nearest the truth refines to it below
      if (const auto run = run_icp(grid, coarse, start, search, true)) {
        slots[k].emplace(landing_share(agreement, coarse, run->T), run->T);
      }
    });
    std::vector<std::pair<double, Eigen::Isometry3d>> found;  // share of the coarse points landing, pose
    for (const auto& slot : slots) {
      if (slot) found.push_back(*slot);
    }
    std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    for (const auto& entry : found) {
      const Eigen::Isometry3d& T = entry.second;  // a named reference: clang 14 cannot capture a binding
      if (seeds.size() >= options.refine_best) break;
      if (std::all_of(seeds.begin(), seeds.end(), [&](const Eigen::Isometry3d& o) { return distinct(o, T); })) {
        seeds.push_back(T);
      }
    }
  }

  struct Candidate {
    IcpRun run;
    std::size_t landing = 0;  // of `dense`'s points: its agreement
  };
  std::vector<std::optional<IcpRun>> refined(seeds.size());
  std::vector<std::size_t> landing(seeds.size(), 0);
  parallel_for(pool, seeds.size(), [&](std::size_t k) {
    refined[k] = run_icp(grid, query_points, seeds[k], options);
    if (refined[k] && refined[k]->converged) landing[k] = agreement.count(dense, refined[k]->T);
  });
  std::vector<Candidate> converged;
  std::optional<IcpRun> first;  // the first seed's run, reported when nothing converges
  for (std::size_t k = 0; k < seeds.size(); ++k) {
    const auto& run = refined[k];
    if (run && !first) first = run;
    if (run && run->converged) converged.push_back({*run, landing[k]});
  }
  if (converged.empty() && !first) return std::nullopt;

  ScanRegistration result;
  result.starts = static_cast<int>(start_count);
  result.converged_starts = static_cast<int>(converged.size());
  if (converged.empty()) {
    result.T_reference_query = first->T;
    result.iterations = first->iterations;
    result.correspondences = first->correspondences;
    result.agreement = landing_share(agreement, dense, first->T);
    return result;  // not converged: no probe
  }
  const auto best = std::max_element(converged.begin(), converged.end(),
                                     [](const Candidate& a, const Candidate& b) { return a.landing < b.landing; });
  result.T_reference_query = best->run.T;
  result.converged = true;
  result.iterations = best->run.iterations;
  result.correspondences = best->run.correspondences;
  result.agreement = share_of(best->landing, dense);
  // the best of the converged results elsewhere (another optimum, not the same one reached twice)
  for (const Candidate& c : converged) {
    if (distinct(best->run.T, c.run.T)) {
      result.runner_up_agreement = std::max(result.runner_up_agreement, share_of(c.landing, dense));
    }
  }

  // The probe: moved along each axis of the reference, the result must lose landing points.
  const std::size_t at_result = best->landing;
  result.min_probe_loss = at_result == 0 ? 0.0 : 1.0;
  for (int axis = 0; axis < 3 && at_result > 0; ++axis) {
    for (const double sign : {-1.0, 1.0}) {
      Eigen::Isometry3d moved = result.T_reference_query;
      moved.translation()[axis] += sign * options.probe_shift_m;
      const std::size_t there = agreement.count(dense, moved);
      const double loss = 1.0 - static_cast<double>(there) / static_cast<double>(at_result);
      result.min_probe_loss = std::min(result.min_probe_loss, std::max(loss, 0.0));
    }
  }
  return result;
}

void GapRegistrationOptions::validate() const {
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  require(non_negative(allowance_m), "gap_registration.allowance_m", ">= 0 m");
  require(non_negative(max_acceleration), "gap_registration.max_acceleration", ">= 0 m/s^2");
  require(non_negative(allowance_deg), "gap_registration.allowance_deg", ">= 0 deg");
  require(non_negative(max_turn_rate_deg_s), "gap_registration.max_turn_rate_deg_s", ">= 0 deg/s");
  require(std::isfinite(min_probe_loss) && min_probe_loss >= 0.0 && min_probe_loss <= 1.0,
          "gap_registration.min_probe_loss", "in [0, 1]");
  require(std::isfinite(max_yaw_search_deg) && max_yaw_search_deg >= 0.0 && max_yaw_search_deg <= 180.0,
          "gap_registration.max_yaw_search_deg", "in [0, 180] deg");
  require(std::isfinite(max_along_search_m) && max_along_search_m >= 0.0 && max_along_search_m <= 100.0,
          "gap_registration.max_along_search_m", "in [0, 100] m");
  require(std::isfinite(max_runner_up_ratio) && max_runner_up_ratio > 0.0 && max_runner_up_ratio <= 1.0,
          "gap_registration.max_runner_up_ratio", "in (0, 1]");
  registration.validate();
}

std::optional<GapRegistration> register_across_gap(PointCloudView reference, PointCloudView query,
                                                   const Eigen::Isometry3d& T_cam_lidar,
                                                   const Eigen::Isometry3d& T_reference_query_guess, double gap_s,
                                                   const GapRegistrationOptions& options, TaskPool* pool) {
  options.validate();
  GapRegistration g;
  g.allowed_m = options.allowed_m(gap_s);
  g.allowed_deg = options.allowed_deg(gap_s);
  ScanRegistrationOptions search = options.registration;
  search.yaw_range_deg = std::min(g.allowed_deg, options.max_yaw_search_deg);
  search.along_range_m = std::min(g.allowed_m, options.max_along_search_m);
  const Eigen::Isometry3d T_lidar_cam = T_cam_lidar.inverse();
  const Eigen::Isometry3d guess = T_lidar_cam * T_reference_query_guess * T_cam_lidar;
  std::optional<ScanRegistration> r = register_scans(reference, query, guess, search, pool);
  if (!r) return std::nullopt;
  g.registration = *r;
  // a rotation to 1e-16 again: KITTI's printed extrinsics are one to ~1e-7, and the tracker chains
  // these motions frame after frame while lost (TrackerOptions::register_lost)
  g.T_reference_query = orthonormalized(T_cam_lidar * r->T_reference_query * T_lidar_cam);
  // the query's move in the reference's LiDAR frame: its origin displaced, its axes turned
  const Eigen::Isometry3d change = guess.inverse() * r->T_reference_query;
  g.moved_m = (r->T_reference_query.translation() - guess.translation()).norm();
  g.moved_deg = rotation_angle(change.linear()) * 180.0 / std::numbers::pi;
  g.accepted = r->converged && r->min_probe_loss >= options.min_probe_loss && g.moved_m <= g.allowed_m &&
               g.moved_deg <= g.allowed_deg && r->runner_up_agreement <= options.max_runner_up_ratio * r->agreement;
  return g;
}

}  // namespace rgbl
