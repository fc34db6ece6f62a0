#include "rgbl/tracking/object_residuals.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rgbl {

void ObjectResidualOptions::validate() const {
  require(std::isfinite(radius_px) && radius_px > 0.0, "tracker.object_test.radius_px", "> 0 px");
  require(std::isfinite(min_tolerance) && min_tolerance >= 0.0, "tracker.object_test.min_tolerance", ">= 0 m");
  require(std::isfinite(relative_tolerance) && relative_tolerance >= 0.0, "tracker.object_test.relative_tolerance",
          ">= 0");
  require(min_points >= 2, "tracker.object_test.min_points", ">= 2");
  require(std::isfinite(chi2) && chi2 > 0.0, "tracker.object_test.chi2", "> 0");
  require(min_objects >= 1, "tracker.object_test.min_objects", ">= 1");
  require(std::isfinite(max_share) && max_share > 0.0 && max_share < 1.0, "tracker.object_test.max_share",
          "in (0, 1)");
}

namespace {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) {
    while (parent[static_cast<std::size_t>(a)] != a) {
      parent[static_cast<std::size_t>(a)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(a)])];
      a = parent[static_cast<std::size_t>(a)];
    }
    return a;
  }
  void join(int a, int b) { parent[static_cast<std::size_t>(find(a))] = find(b); }
};

}  // namespace

ObjectResiduals objects_against_pose(const PinholeCamera& camera, const Eigen::Isometry3d& T_cam_world,
                                     std::span<const PoseObservation> observations, const std::vector<bool>& inlier,
                                     const std::vector<bool>& exclude, const ObjectResidualOptions& options,
                                     bool bounded_depth_error) {
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
  UnionFind groups(n);
  const double r2 = options.radius_px * options.radius_px;
  for (std::size_t a = 0; a < n; ++a) {
    const PoseObservation& oa = observations[tested[a]];
    const double tolerance = std::max(options.min_tolerance, options.relative_tolerance * oa.depth);
    for (std::size_t b = a + 1; b < n; ++b) {
      const PoseObservation& ob = observations[tested[b]];
      if ((oa.pixel - ob.pixel).squaredNorm() > r2 || std::abs(oa.depth - ob.depth) > tolerance) continue;
      groups.join(static_cast<int>(a), static_cast<int>(b));
    }
  }
  std::vector<std::vector<std::size_t>> members(n);
  for (std::size_t a = 0; a < n; ++a) members[static_cast<std::size_t>(groups.find(static_cast<int>(a)))].push_back(a);
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
    if (static_cast<double>(m.size()) >= limit || static_cast<double>(taken + m.size()) >= limit) continue;
    taken += m.size();
    ++out.flagged_objects;
    for (const std::size_t a : m) out.flagged[tested[a]] = true;
  }
  return out;
}

}  // namespace rgbl
