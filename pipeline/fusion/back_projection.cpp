#include "pipeline/fusion/back_projection.h"

#include <omp.h>

#include <array>
#include <cmath>
#include <vector>

#include "common/error.h"
#include "pipeline/fusion/fusion_kernels.h"

namespace cenote::pipeline {
namespace {

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
      count += detail::countPoints(frame.depth.ptr<float>(y), cols);
    }
    offset[b + 1] = count;
  }
  for (int b = 0; b < blocks; ++b) offset[b + 1] += offset[b];
  // Growing, a batch takes an eighth more than it needs: one reused frame after frame (the
  // runner's, frame_pipeline.h) then stops reallocating as the number of points varies.
  const size_t count = offset[blocks];
  if (out.points.capacity() < count) out.points.reserve(count + count / 8);
  if (colored && out.colors.capacity() < count) out.colors.reserve(count + count / 8);
  out.points.resize(count);
  out.colors.resize(colored ? count : 0);
  if (out.points.empty()) return;

  // Eigen::Vector3f is three contiguous floats, std::array<uint8_t, 3> three bytes.
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float) && sizeof(std::array<uint8_t, 3>) == 3);
  float* const xyz = out.points.data()->data();
  uint8_t* const rgb = colored ? out.colors.data()->data() : nullptr;
#pragma omp parallel for num_threads(blocks) schedule(static, 1)
  for (int b = 0; b < blocks; ++b) {
    size_t i = offset[b];
    for (int y = blockStart(rows, blocks, b); y < blockStart(rows, blocks, b + 1); ++y) {
      const Eigen::Vector3f row_ray = RK_inv.col(1) * static_cast<float>(y) + RK_inv.col(2);
      const detail::RowRays rays{
          {row_ray.x(), row_ray.y(), row_ray.z()}, {RK_inv(0, 0), RK_inv(1, 0), RK_inv(2, 0)}, {t.x(), t.y(), t.z()}};
      i += detail::backProjectRow(rays, frame.depth.ptr<float>(y), colored ? frame.color.ptr<uint8_t>(y) : nullptr, cols,
                                  xyz + 3 * i, rgb ? rgb + 3 * i : nullptr, offset[b + 1] - i);
    }
  }
}

}  // namespace cenote::pipeline
