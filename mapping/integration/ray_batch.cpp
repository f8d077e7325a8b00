#include "mapping/integration/ray_batch.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

// The grid a ray is marched on: cells of 2^(3 - kShift) voxels per side, 2^kShift per block side
// (kShift 3: voxels; 2: the 2x2x2-voxel cells of coarse clearing, 5.; cell c holds voxels 2c and
// 2c + 1 on each axis). A cell is 2^(3 - kShift) consecutive words of its block's free mask (x)
// with the same bit pattern (y, z) in each.
template <int kShift>
struct CellGrid {
  static_assert(kShift == 2 || kShift == 3);
  static constexpr int kInBlock = (1 << kShift) - 1;  // mask of an in-block cell coordinate
  static BlockIndex blockOf(const VoxelIndex& c) {
    return BlockIndex(c.x() >> kShift, c.y() >> kShift, c.z() >> kShift);
  }
  static uint64_t* words(BlockMasks* masks, int lx) { return masks->free.data() + (lx << (3 - kShift)); }
  static uint64_t pattern(int ly, int lz) {
    if constexpr (kShift == 3) return 1ull << ((ly << 3) | lz);
    return 0x303ull << ((ly << 4) | (lz << 1));
  }
};

// The cells of side cell_m (CellGrid<kShift>) from the cell of start_m towards the cell of end_m:
// for voxels, those of walkVoxels(start_m, end_m, voxel_size_m, include_end) (voxel_ray.h) in the
// same order with the same tie rules, so that ray_stop_run 0 stays OctoMap's voxel set. Made for
// the hot loop: the state stays in registers, and the current block's masks are looked up only
// when the walk crosses into another block (about every 2^kShift steps).
// Visit: bool operator()(uint64_t* words, uint64_t pattern) on the cell's words, false to stop.
// Returns false when the visitor stopped the walk.
template <int kShift, typename Visit>
bool march(const Eigen::Vector3d& start_m, const Eigen::Vector3d& end_m, double cell_m, bool include_end,
           BatchUpdates& writer, Visit visit) {
  using Grid = CellGrid<kShift>;
  const VoxelIndex key_start = toVoxel(start_m, cell_m);
  const VoxelIndex key_end = toVoxel(end_m, cell_m);
  auto visitCell = [&](const VoxelIndex& c) {
    constexpr int m = Grid::kInBlock;
    return visit(Grid::words(writer.masksOf(Grid::blockOf(c)), c.x() & m), Grid::pattern(c.y() & m, c.z() & m));
  };
  if (key_start == key_end) return include_end ? visitCell(key_end) : true;
  Eigen::Vector3d direction = end_m - start_m;
  const double length = direction.norm();
  direction /= length;
  int step[3];
  double t_max[3], t_delta[3];
  for (int i = 0; i < 3; ++i) {
    step[i] = direction[i] > 0.0 ? 1 : (direction[i] < 0.0 ? -1 : 0);
    if (step[i] != 0) {
      const double border = (key_start[i] + 0.5) * cell_m + step[i] * cell_m * 0.5;
      t_max[i] = (border - start_m[i]) / direction[i];
      t_delta[i] = cell_m / std::fabs(direction[i]);
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = 0.0;  // never stepped: t_max stays at max
    }
  }
  // In-block coordinates and the block; a step that wraps an in-block coordinate moves to the
  // neighbouring block.
  constexpr int kWrap = ~Grid::kInBlock;
  int lx = key_start.x() & Grid::kInBlock, ly = key_start.y() & Grid::kInBlock, lz = key_start.z() & Grid::kInBlock;
  BlockIndex block = Grid::blockOf(key_start);
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  const double dx = t_delta[0], dy = t_delta[1], dz = t_delta[2];
  const int sx = step[0], sy = step[1], sz = step[2];
  BlockMasks* masks = writer.masksOf(block);
  if (!visit(Grid::words(masks, lx), Grid::pattern(ly, lz))) return false;
  // Each step moves one cell towards the end cell on one axis, so the walk can be in the end cell
  // only after exactly this many steps (and never, if rounding made an axis overshoot).
  const long steps_to_end = (key_end - key_start).cwiseAbs().sum();
  const long max_steps = 3 * static_cast<long>(length / cell_m) + 6;
  for (long n = 1; n <= max_steps; ++n) {
    // walkVoxels' choice: x if t_x < t_y and t_x < t_z; else y if t_y < t_z; else z.
    bool crossed;
    if (tx < ty && tx < tz) {
      lx += sx;
      tx += dx;
      crossed = (lx & kWrap) != 0;
      if (crossed) {
        block.x() += sx;
        lx &= Grid::kInBlock;
      }
    } else if (ty < tz) {
      ly += sy;
      ty += dy;
      crossed = (ly & kWrap) != 0;
      if (crossed) {
        block.y() += sy;
        ly &= Grid::kInBlock;
      }
    } else {
      lz += sz;
      tz += dz;
      crossed = (lz & kWrap) != 0;
      if (crossed) {
        block.z() += sz;
        lz &= Grid::kInBlock;
      }
    }
    if (n == steps_to_end && VoxelIndex((block.x() << kShift) + lx, (block.y() << kShift) + ly,
                                        (block.z() << kShift) + lz) == key_end) {
      return include_end ? visitCell(key_end) : true;
    }
    if (std::min(std::min(tx, ty), tz) > length) {
      // Left the segment without entering the end cell (it ends on a face or an edge).
      return include_end ? visitCell(key_end) : true;
    }
    if (crossed) masks = writer.masksOf(block);
    if (!visit(Grid::words(masks, lx), Grid::pattern(ly, lz))) return false;
  }
  return true;
}

// Visitors of march<3> (voxels). Whole rays: every voxel is free.
struct CarveAll {
  bool operator()(uint64_t* word, uint64_t bit) const {
    *word |= bit;
    return true;
  }
};
// From the end back to the origin (the end voxel itself is not free), until stop_run voxels in a
// row were already carved by earlier rays of the chunk: from there on they have carved (nearly)
// the same path.
struct CarveUntilRun {
  int stop_run;
  int run = 0;
  bool at_end_voxel = true;
  bool operator()(uint64_t* word, uint64_t bit) {
    if (at_end_voxel) {
      at_end_voxel = false;
      return true;
    }
    // Without a branch on "already carved": it alternates irregularly along a ray.
    const int carved = (*word & bit) != 0;
    *word |= bit;
    run = (run + 1) & -carved;
    return run < stop_run;
  }
};

// The counterpart of CarveUntilRun on 2-voxel cells (march<2>): stops after stop_run cells in a
// row whose 8 voxels were all carved already.
struct CarveCellsUntilRun {
  int stop_run;
  int run = 0;
  bool operator()(uint64_t* words, uint64_t pattern) {
    const int carved = ((words[0] & pattern) == pattern) & ((words[1] & pattern) == pattern);
    words[0] |= pattern;
    words[1] |= pattern;
    run = (run + 1) & -carved;
    return run < stop_run;
  }
};

}  // namespace

void RayBatch::build(const PointBatch& batch, double voxel_size_m, double max_range_m, int num_threads, int stop_run) {
  const bool exact = stop_run <= 0;
  // 1. A fixed number of chunks of consecutive points (image bands), each deduplicated and marched
  // into its own masks by any thread, so that the result does not depend on the thread count. In
  // exact mode every ray is marched whole, so any split gives the same union: one chunk per thread.
  const int threads = std::max(1, num_threads > 0 ? num_threads : omp_get_max_threads());
  const int num_chunks = exact ? threads : kRayChunks;
  if (chunks_.size() < static_cast<size_t>(num_chunks)) chunks_.resize(num_chunks);
  const Eigen::Vector3d origin = batch.origin;
  const bool limited = max_range_m > 0.0;
  const size_t n = batch.points.size();
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int c = 0; c < num_chunks; ++c) {
    Chunk& chunk = chunks_[c];
    chunk.updates.clearMasks();
    chunk.endpoints.clear();
    for (size_t i = n * c / num_chunks; i < n * (c + 1) / num_chunks; ++i) {
      chunk.endpoints.add(toVoxel(batch.points[i].cast<double>(), voxel_size_m),
                          batch.hasColor() ? batch.colors[i].data() : nullptr);
    }
    BatchUpdates& writer = chunk.updates;
    for (const VoxelIndex& endpoint : chunk.endpoints.voxels()) {
      const Eigen::Vector3d end = voxelCentre(endpoint, voxel_size_m);
      const Eigen::Vector3d ray = end - origin;
      const double range = ray.norm();
      const bool in_range = !limited || range <= max_range_m;
      const Eigen::Vector3d stop = in_range ? end : Eigen::Vector3d(origin + ray * (max_range_m / range));
      if (exact) {
        march<3>(origin, stop, voxel_size_m, false, writer, CarveAll{});
      } else {
        // Voxel by voxel for the last kFineVoxels before the end, then by 2-voxel cells (5.).
        const double fine_m = RayBatch::kFineVoxels * voxel_size_m;
        const double length = (stop - origin).norm();
        if (length <= fine_m + 2.0 * voxel_size_m) {
          march<3>(stop, origin, voxel_size_m, true, writer, CarveUntilRun{stop_run});
        } else {
          const Eigen::Vector3d coarse_start = stop + (origin - stop) * (fine_m / length);
          if (march<3>(stop, coarse_start, voxel_size_m, false, writer, CarveUntilRun{stop_run})) {
            march<2>(coarse_start, origin, 2.0 * voxel_size_m, true, writer,
                     CarveCellsUntilRun{std::max(1, stop_run / 2)});
          }
        }
      }
      if (in_range) writer.setHit(endpoint);
    }
  }
  num_rays_ = 0;
  for (int c = 0; c < num_chunks; ++c) num_rays_ += chunks_[c].endpoints.voxels().size();

  // 2. Union of the chunks' masks, taken over from chunk 0.
  for (int c = 1; c < num_chunks; ++c) chunks_[0].updates.unite(chunks_[c].updates);
  updates_.swapMasks(chunks_[0].updates);

  // 3. Mean colours of the hit voxels, over all chunks (an endpoint voxel may span two bands);
  // finish() keeps those whose hit bit is set, i.e. the endpoints within range.
  endpoints_.clear();
  if (batch.hasColor()) {
    for (int c = 0; c < num_chunks; ++c) endpoints_.merge(chunks_[c].endpoints);
  }
  updates_.finish(endpoints_, batch.hasColor());
}

}  // namespace cenote::mapping
