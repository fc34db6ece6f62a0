#include "rgbl/geometry/projection.hpp"

#include "rgbl/core/cpu_dispatch.hpp"
#include "rgbl/core/error.hpp"

#include <algorithm>
#include <array>
#include <cstdint>

namespace rgbl {

void ProjectionOptions::validate() const {
  require(min_depth >= 0.0F, "projection.min_depth", "a depth >= 0 m");
  require(max_depth > min_depth, "projection.max_depth", "a depth greater than projection.min_depth");
}

namespace {

constexpr std::size_t kBlock = 128;

struct ProjectionParams {
  std::array<float, 12> m;  // P_img_lidar, row-major
  float min_depth, max_depth, width, height;
  std::int32_t stride;      // floats per image row
};

// A branch-free, vectorisable transform of one block of points into pixel indices (-1: dropped) and
// depths. Scans come in azimuth order, so most blocks lie wholly behind the camera: a cheap depth-only
// pass skips them (about 70% of a KITTI scan's points are never in front of the camera). Returns
// whether any point of the block is in front.
RGBL_CLONES_AVX512 bool transform_block(const LidarPoint* __restrict block, std::size_t count,
                                        const ProjectionParams& p, std::int32_t* __restrict index,
                                        float* __restrict depth_of) {
  // Locals, so the compiler knows the stores below cannot change them.
  const float m0 = p.m[0], m1 = p.m[1], m2 = p.m[2], m3 = p.m[3], m4 = p.m[4], m5 = p.m[5], m6 = p.m[6],
              m7 = p.m[7], m8 = p.m[8], m9 = p.m[9], m10 = p.m[10], m11 = p.m[11];
  const float min_depth = p.min_depth, max_depth = p.max_depth, width = p.width, height = p.height;
  const std::int32_t stride = p.stride;
  int in_front = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const float z = m8 * block[i].x + m9 * block[i].y + m10 * block[i].z + m11;
    in_front += static_cast<int>(z > min_depth);
  }
  if (in_front == 0) return false;
  for (std::size_t i = 0; i < count; ++i) {
    const float x = block[i].x, y = block[i].y, zl = block[i].z;
    const float z = m8 * x + m9 * y + m10 * zl + m11;
    const float inv_z = 1.0F / z;
    // +0.5 then truncation rounds to the nearest pixel centre once the value is known to be >= 0.
    const float u = (m0 * x + m1 * y + m2 * zl + m3) * inv_z + 0.5F;
    const float v = (m4 * x + m5 * y + m6 * zl + m7) * inv_z + 0.5F;
    // Written so that NaN fails every comparison: non-finite points drop out here.
    const bool inside = (z > min_depth) & (z < max_depth) & (u >= 0.0F) & (u < width) & (v >= 0.0F) & (v < height);
    const float uc = inside ? u : 0.0F;
    const float vc = inside ? v : 0.0F;
    const auto cell = static_cast<std::int32_t>(vc) * stride + static_cast<std::int32_t>(uc);
    index[i] = inside ? cell : -1;
    depth_of[i] = z;
  }
  return true;
}

}  // namespace

int project_to_depth(PointCloudView cloud, const Matrix34d& P_img_lidar, const ProjectionOptions& options,
                     cv::Mat_<float>& depth) {
  depth.setTo(0.0F);
  const int width = depth.cols;
  const int height = depth.rows;
  if (width == 0 || height == 0) return 0;

  // Single precision is ample here (sub-millipixel at 100 m) and halves the arithmetic cost.
  ProjectionParams params{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) params.m[static_cast<std::size_t>(r * 4 + c)] = static_cast<float>(P_img_lidar(r, c));
  params.min_depth = options.min_depth;
  params.max_depth = options.max_depth;
  params.width = static_cast<float>(width);
  params.height = static_cast<float>(height);
  params.stride = static_cast<std::int32_t>(depth.step1());
  float* const data = depth.ptr<float>(0);
  int filled = 0;

  // Two passes per block: the vectorised transform, then the data-dependent z-buffer scatter. Blocks
  // keep the scratch arrays in L1.
  alignas(64) std::array<std::int32_t, kBlock> index{};
  alignas(64) std::array<float, kBlock> depth_of{};
  const LidarPoint* const points = cloud.data();
  for (std::size_t begin = 0; begin < cloud.size(); begin += kBlock) {
    const std::size_t count = std::min(kBlock, cloud.size() - begin);
    if (!transform_block(points + begin, count, params, index.data(), depth_of.data())) continue;
    for (std::size_t i = 0; i < count; ++i) {
      if (index[i] < 0) continue;
      float& cell = data[index[i]];
      const float z = depth_of[i];
      if (cell == 0.0F) {
        cell = z;
        ++filled;
      } else if (z < cell) {
        cell = z;
      }
    }
  }
  return filled;
}

cv::Mat_<float> project_to_depth(PointCloudView cloud, const Matrix34d& P_img_lidar, int width, int height,
                                 const ProjectionOptions& options) {
  cv::Mat_<float> depth(height, width);
  project_to_depth(cloud, P_img_lidar, options, depth);
  return depth;
}

}  // namespace rgbl
