#include "rgbl/tracking/object_residuals.hpp"

#include "rgbl/core/disjoint_sets.hpp"
#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rgbl {

void ObjectResidualOptions::validate() const {
  require(min_points >= 2, "tracker.object_test.min_points", ">= 2");
  require(std::isfinite(chi2) && chi2 > 0.0, "tracker.object_test.chi2", "> 0");
  require(min_objects >= 1, "tracker.object_test.min_objects", ">= 1");
  require(std::isfinite(max_share) && max_share > 0.0 && max_share < 1.0, "tracker.object_test.max_share",
          "in (0, 1)");
}

ObjectResiduals objects_against_pose(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world,
                                     std::span<const PoseObservation> observations, const std::vector<bool>& inlier,
                                     const std::vector<bool>& exclude, const ObjectGrouping& grouping,
                                     const ObjectResidualOptions& options, bool bounded_depth_error) {
  ObjectResiduals out;
  out.flagged.assign(observations.size(), false);
  // the tested observations and their whitened residuals
  std::vector<std::size_t> tested;
  std::vector<Eigen::Vector3d> residuals;
  for (std::size_t j = 0; j < observations.size(); ++j) {
    const PoseObservation& o = observations[j];
    if (!inlier[j] || o.depth <= 0.0 || (!exclude.empty() && exclude[j])) continue;
    Eigen::Vector3d r;
    Eigen::Matrix<double, 3, 6> jacobian;
    int dimension = 0;
    if (!pose_residual(camera, T_cam_world, o, r, jacobian, dimension, bounded_depth_error) || dimension != 3) continue;
    tested.push_back(j);
    residuals.push_back(r);
  }
  const std::size_t n = tested.size();
  if (n < static_cast<std::size_t>(options.min_points)) return out;
  // depth-continuous neighbours in the image: one rigid surface
  DisjointSets groups(n);
  const double r2 = grouping.radius_px * grouping.radius_px;
  for (std::size_t a = 0; a < n; ++a) {
    const PoseObservation& oa = observations[tested[a]];
    const double tolerance = std::max(grouping.min_tolerance, grouping.relative_tolerance * oa.depth);
    for (std::size_t b = a + 1; b < n; ++b) {
      const PoseObservation& ob = observations[tested[b]];
      if ((oa.pixel - ob.pixel).squaredNorm() > r2 || std::abs(oa.depth - ob.depth) > tolerance) continue;
      groups.join(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
    }
  }
  std::vector<std::vector<std::size_t>> members(n);
  for (std::size_t a = 0; a < n; ++a) members[groups.root(static_cast<std::uint32_t>(a))].push_back(a);
  struct Object {
    double statistic;
    std::size_t root;
  };
  std::vector<Object> objects;
  for (std::size_t root = 0; root < n; ++root) {
    const auto& m = members[root];
    if (m.size() < static_cast<std::size_t>(options.min_points)) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const std::size_t a : m) sum += residuals[a];
    objects.push_back({sum.squaredNorm() / static_cast<double>(m.size()), root});
  }
  out.objects = static_cast<int>(objects.size());
  if (out.objects < options.min_objects) return out;
  std::vector<double> statistics;
  for (const Object& o : objects) statistics.push_back(o.statistic);
  const auto middle = statistics.begin() + static_cast<std::ptrdiff_t>(statistics.size() / 2);
  std::nth_element(statistics.begin(), middle, statistics.end());
  constexpr double chi2_3_median = 2.366;
  out.overdispersion = std::max(1.0, *middle / chi2_3_median);
  std::sort(objects.begin(), objects.end(), [](const Object& a, const Object& b) { return a.statistic > b.statistic; });
  const double limit = options.max_share * static_cast<double>(n);
  std::size_t taken = 0;
  for (const Object& o : objects) {
    if (o.statistic <= options.chi2 * out.overdispersion) break;
    const auto& m = members[o.root];
    if (static_cast<double>(taken + m.size()) >= limit) continue;  // each, and all of them together
    taken += m.size();
    ++out.flagged_objects;
    for (const std::size_t a : m) out.flagged[tested[a]] = true;
  }
  return out;
}

}  // namespace rgbl
