#include "pipeline/fusion/back_projection.h"

#include <omp.h>

#include <array>
#include <cmath>
#include <vector>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

// Both comparisons always evaluated (no short circuit), so the counting loop vectorises.
bool hasPoint(float depth_m) { return (depth_m > 0.0f) & (depth_m < std::numeric_limits<float>::infinity()); }

// Rows [begin, end) of block b out of `blocks` equal blocks.
int blockStart(int rows, int blocks, int b) { return static_cast<int>(static_cast<long>(rows) * b / blocks); }

}  // namespace

void backProject(const DepthFrame& frame, PointBatch& out) {
  if (frame.depth.type() != CV_32FC1) throw Error("backProject: depth map must be CV_32FC1");
  const bool colored = !frame.color.empty();
  if (colored && (frame.color.type() != CV_8UC3 || frame.color.size() != frame.depth.size())) {
    throw Error("backProject: colour image must be CV_8UC3 of the depth map's size");
  }
  out.t_s = frame.t_s;
  out.origin = frame.T_world_cam.translation();
  const int rows = frame.depth.rows, cols = frame.depth.cols;
  // p_world = R (z K^-1 [x y 1]^T) + t = z (R K^-1 [0 y 1]^T + x R K^-1 e_x) + t, in float (the
  // points are float; t is exact to float precision like the result).
  const Eigen::Matrix3f RK_inv = (frame.T_world_cam.linear() * frame.K.inverse()).cast<float>();
  const Eigen::Vector3f t = frame.T_world_cam.translation().cast<float>();
  // Two passes over contiguous row blocks (count, then fill at the block's offset): the order is
  // row-major and no thread writes where another does.
  constexpr int kMaxBlocks = 64;
  const int blocks = std::max(1, std::min({omp_get_max_threads(), kMaxBlocks, rows}));
  std::array<size_t, kMaxBlocks + 1> offset{};
#pragma omp parallel for num_threads(blocks) schedule(static, 1)
  for (int b = 0; b < blocks; ++b) {
    size_t count = 0;
    for (int y = blockStart(rows, blocks, b); y < blockStart(rows, blocks, b + 1); ++y) {
      const float* depth = frame.depth.ptr<float>(y);
      for (int x = 0; x < cols; ++x) count += hasPoint(depth[x]);
    }
    offset[b + 1] = count;
  }
  for (int b = 0; b < blocks; ++b) offset[b + 1] += offset[b];
  out.points.resize(offset[blocks]);
  out.colors.resize(colored ? offset[blocks] : 0);

  Eigen::Vector3f* const points = out.points.data();
  std::array<uint8_t, 3>* const colors = out.colors.data();
#pragma omp parallel for num_threads(blocks) schedule(static, 1)
  for (int b = 0; b < blocks; ++b) {
    size_t i = offset[b];
    for (int y = blockStart(rows, blocks, b); y < blockStart(rows, blocks, b + 1); ++y) {
      const float* depth = frame.depth.ptr<float>(y);
      const uint8_t* bgr = colored ? frame.color.ptr<uint8_t>(y) : nullptr;
      // Per component: ray = (RK_inv e_y y + RK_inv e_z) + x RK_inv e_x, p = z ray + t, the
      // operations of the Eigen expressions in this order (no fused multiply-add).
      const Eigen::Vector3f row_ray = RK_inv.col(1) * static_cast<float>(y) + RK_inv.col(2);
      const float r0 = row_ray.x(), r1 = row_ray.y(), r2 = row_ray.z();
      const float s0 = RK_inv(0, 0), s1 = RK_inv(1, 0), s2 = RK_inv(2, 0);
      for (int x = 0; x < cols; ++x) {
        const float z = depth[x];
        if (!hasPoint(z)) continue;
        const float xf = static_cast<float>(x);
        points[i] = Eigen::Vector3f(z * (r0 + xf * s0) + t.x(), z * (r1 + xf * s1) + t.y(), z * (r2 + xf * s2) + t.z());
        if (colored) colors[i] = {bgr[3 * x + 2], bgr[3 * x + 1], bgr[3 * x]};
        ++i;
      }
    }
  }
}

}  // namespace cenote::pipeline
