#include "mapping/integration/projective_batch.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

bool hasDepth(float d) { return d > 0.0f && std::isfinite(d); }

// Side planes of the frustum in the camera frame, as inward unit normals through the centre.
std::array<Eigen::Vector3d, 4> sidePlanes(const DepthFrame& f) {
  const double u0 = (-0.5 - f.cx) / f.fx, u1 = (f.width - 0.5 - f.cx) / f.fx;
  const double v0 = (-0.5 - f.cy) / f.fy, v1 = (f.height - 0.5 - f.cy) / f.fy;
  return {Eigen::Vector3d(1.0, 0.0, -u0).normalized(), Eigen::Vector3d(-1.0, 0.0, u1).normalized(),
          Eigen::Vector3d(0.0, 1.0, -v0).normalized(), Eigen::Vector3d(0.0, -1.0, v1).normalized()};
}

}  // namespace

void ProjectiveBatch::build(const DepthFrame& f, double s, double max_range_m, int num_threads) {
  const bool limited = max_range_m > 0.0;
  const Eigen::Vector3d origin = f.T_world_cam.translation();
  const Eigen::Matrix3d R = f.T_world_cam.linear();

  // 1. Hits: the voxel of every back-projected point within range, with colour sums (last voxel
  // cached: neighbouring pixels mostly share one).
  updates_.clearMasks();
  endpoints_.clear();
  num_hits_ = 0;
  double max_depth = 0.0;
  for (int v = 0; v < f.height; ++v) {
    for (int u = 0; u < f.width; ++u) {
      const size_t i = static_cast<size_t>(v) * f.width + u;
      const float d = f.depth_m[i];
      if (!hasDepth(d)) continue;
      max_depth = std::max(max_depth, static_cast<double>(d));
      const Eigen::Vector3d p_cam(d * (u - f.cx) / f.fx, d * (v - f.cy) / f.fy, d);
      if (limited && p_cam.norm() > max_range_m) continue;
      ++num_hits_;
      endpoints_.add(toVoxel(f.T_world_cam * p_cam, s), f.hasColor() ? f.colors[i].data() : nullptr);
    }
  }

  // 2. Frustum blocks: bounding box of the frustum up to the deepest free voxel, then a sphere test
  // against the near plane, the far depth and the four side planes.
  const double far_z = limited ? std::min(max_depth, max_range_m) : max_depth;
  candidates_.clear();
  if (far_z > 0.0) {
    Aabb box;
    box.extend(origin);
    for (double u : {-0.5, f.width - 0.5}) {
      for (double v : {-0.5, f.height - 0.5}) {
        box.extend(f.T_world_cam * Eigen::Vector3d(far_z * (u - f.cx) / f.fx, far_z * (v - f.cy) / f.fy, far_z));
      }
    }
    const BlockIndex lo = blockOf(toVoxel(box.min_m, s)), hi = blockOf(toVoxel(box.max_m, s));
    const auto planes = sidePlanes(f);
    const double block_m = kBlockSide * s, radius = 0.5 * std::sqrt(3.0) * block_m;
    for (int bx = lo.x(); bx <= hi.x(); ++bx) {
      for (int by = lo.y(); by <= hi.y(); ++by) {
        for (int bz = lo.z(); bz <= hi.z(); ++bz) {
          const Eigen::Vector3d centre = (Eigen::Vector3d(bx, by, bz).array() + 0.5).matrix() * block_m;
          const Eigen::Vector3d c = R.transpose() * (centre - origin);
          if (c.z() < -radius || c.z() - radius > far_z) continue;
          if (limited && c.norm() - radius > max_range_m) continue;
          bool inside = true;
          for (const auto& n : planes) inside &= n.dot(c) >= -radius;
          if (inside) candidates_.emplace_back(bx, by, bz);
        }
      }
    }
  }
  num_frustum_blocks_ = candidates_.size();

  // 3. Free voxels of each frustum block, blocks in parallel (each written by one thread only).
  candidate_masks_.assign(candidates_.size(), BlockMasks{});
  const int threads = std::max(1, num_threads > 0 ? num_threads : omp_get_max_threads());
  const Eigen::Matrix3d Rt = R.transpose();
  const Eigen::Vector3d step_x = Rt.col(0) * s, step_y = Rt.col(1) * s, step_z = Rt.col(2) * s;
  const double max_range2 = limited ? max_range_m * max_range_m : std::numeric_limits<double>::infinity();
  const long num_candidates = static_cast<long>(candidates_.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 16)
  for (long b = 0; b < num_candidates; ++b) {
    const VoxelIndex first = candidates_[b] * kBlockSide;
    const Eigen::Vector3d p0 = Rt * (voxelCentre(first, s) - origin);  // camera frame
    BlockMasks& out = candidate_masks_[b];
    for (int x = 0; x < kBlockSide; ++x) {
      for (int y = 0; y < kBlockSide; ++y) {
        Eigen::Vector3d p = p0 + x * step_x + y * step_y;
        uint64_t bits = 0;
        for (int z = 0; z < kBlockSide; ++z, p += step_z) {
          if (p.z() <= 0.0 || p.squaredNorm() > max_range2) continue;
          const double u = f.fx * p.x() / p.z() + f.cx, v = f.fy * p.y() / p.z() + f.cy;
          const double pu = std::floor(u + 0.5), pv = std::floor(v + 0.5);
          if (pu < 0.0 || pv < 0.0 || pu >= f.width || pv >= f.height) continue;
          const float d = f.depth_m[static_cast<size_t>(pv) * f.width + static_cast<size_t>(pu)];
          if (!hasDepth(d) || p.z() > d - s) continue;
          bits |= 1ull << (y * kBlockSide + z);
        }
        out.free[x] |= bits;
      }
    }
  }

  // 4. Free blocks and hit voxels into one table; occupied wins; mean colours of the hit voxels.
  for (size_t b = 0; b < candidates_.size(); ++b) {
    const BlockMasks& m = candidate_masks_[b];
    if (std::all_of(m.free.begin(), m.free.end(), [](uint64_t w) { return w == 0; })) continue;
    updates_.masksOf(candidates_[b])->free = m.free;
  }
  for (const VoxelIndex& ijk : endpoints_.voxels()) updates_.setHit(ijk);
  updates_.finish(endpoints_, f.hasColor());
}

}  // namespace cenote::mapping
