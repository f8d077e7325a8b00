#include "mapping/integration/ray_batch.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

// One ray on the voxel grid, from `origin_m` to `end_m`, as the crossings of voxel faces by the
// segment p(t) = origin + t d, d = end - origin, t in [0, 1]. The crossing of the face plane x = b s
// (b an integer; likewise y, z) is at t = b a - c with a = s / d_x, c = origin_x / d_x: one formula,
// evaluated the same way whichever way the ray is walked, and increasing with the face crossed on
// each axis (b a and then b a - c round monotonically). Walked from the origin, the crossings come
// in order of increasing t, ties to the highest axis (z before y before x: OctoMap's computeRayKeys);
// walked from the end, in the exact reverse order (decreasing t, ties to the lowest axis). So both
// walks visit the same voxels, whatever the rounding, and a walk from the end that stops early
// visits only voxels of the whole ray (ray_batch.h, 3.). Each axis steps exactly as often as the
// end voxel is away from the origin's on it: the walk always ends in the end voxel.
// Made for the hot loop: the state stays in registers, and the current block's masks are looked up
// only when the walk crosses into another block (about every 8 steps).
struct RayWalk {
  VoxelIndex key_origin, key_end;
  int step[3];        // +-1 along the ray, 0 for an axis it never steps on
  long count[3];      // steps on each axis from the origin's voxel to the end's
  double a[3], c[3];  // t of face b on axis i: b a[i] - c[i]

  RayWalk(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& end_m, double s)
      : key_origin(toVoxel(origin_m, s)), key_end(toVoxel(end_m, s)) {
    const Eigen::Vector3d d = end_m - origin_m;
    for (int i = 0; i < 3; ++i) {
      const long n = static_cast<long>(key_end[i]) - key_origin[i];
      step[i] = n > 0 ? 1 : (n < 0 ? -1 : 0);
      count[i] = n < 0 ? -n : n;
      // Distinct voxels on an axis mean distinct coordinates: d[i] != 0 where count[i] > 0.
      a[i] = count[i] > 0 ? s / d[i] : 0.0;
      c[i] = count[i] > 0 ? origin_m[i] / d[i] : 0.0;
    }
  }
  long steps() const { return count[0] + count[1] + count[2]; }
  double faceT(int i, double b) const { return b * a[i] - c[i]; }
};

// A voxel's word of its block's free mask and its bit in it.
inline uint64_t* freeWord(BlockMasks* masks, int lx) { return masks->free.data() + lx; }
inline uint64_t voxelBit(int ly, int lz) { return 1ull << ((ly << 3) | lz); }

// One step of a walk across the next face on one axis: the in-block coordinate `l` and the face
// index `b` move by `step` (+-1), `t` becomes that of the axis' next face (`never` once `n`, the
// steps left on the axis, runs out), and a coordinate that wraps moves `block_coord` to the
// neighbouring block. Returns whether it did.
inline bool stepAcrossFace(int& l, double& b, double& t, long& n, int step, double a, double c, double never,
                           int& block_coord) {
  l += step;
  b += step;
  t = --n > 0 ? b * a - c : never;
  if ((l & ~7) == 0) return false;
  block_coord += step;
  l &= 7;
  return true;
}

// The voxels of the ray from origin_m to end_m, from the origin's voxel up to the end's, exclusive
// (OctoMap's free-space rule; nothing when both share a voxel): visit(word, bit) on each, in order;
// false stops the walk. Returns false when the visitor stopped it.
template <typename Visit>
bool marchFromOrigin(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& end_m, double voxel_size_m,
                     BatchUpdates& writer, Visit visit) {
  const RayWalk w(origin_m, end_m, voxel_size_m);
  const long steps = w.steps();
  if (steps == 0) return true;
  constexpr double kNever = std::numeric_limits<double>::infinity();
  // The next face on each axis (its index as a double: exact, and no conversion in the loop), the
  // t of crossing it, and the steps left on the axis.
  double bx = w.key_origin.x() + (w.step[0] > 0), by = w.key_origin.y() + (w.step[1] > 0),
         bz = w.key_origin.z() + (w.step[2] > 0);
  long nx = w.count[0], ny = w.count[1], nz = w.count[2];
  double tx = nx > 0 ? w.faceT(0, bx) : kNever, ty = ny > 0 ? w.faceT(1, by) : kNever,
         tz = nz > 0 ? w.faceT(2, bz) : kNever;
  const double ax = w.a[0], ay = w.a[1], az = w.a[2], cx = w.c[0], cy = w.c[1], cz = w.c[2];
  const int sx = w.step[0], sy = w.step[1], sz = w.step[2];
  int lx = w.key_origin.x() & 7, ly = w.key_origin.y() & 7, lz = w.key_origin.z() & 7;
  BlockIndex block = blockOf(w.key_origin);
  BlockMasks* masks = writer.masksOf(block);
  if (!visit(freeWord(masks, lx), voxelBit(ly, lz))) return false;
  // In-block coordinates and the block; a step that wraps an in-block coordinate moves to the
  // neighbouring block. The last step enters the end voxel, which is not visited.
  for (long n = 1; n < steps; ++n) {
    bool crossed;
    if (tx < ty && tx < tz) {
      crossed = stepAcrossFace(lx, bx, tx, nx, sx, ax, cx, kNever, block.x());
    } else if (ty < tz) {
      crossed = stepAcrossFace(ly, by, ty, ny, sy, ay, cy, kNever, block.y());
    } else {
      crossed = stepAcrossFace(lz, bz, tz, nz, sz, az, cz, kNever, block.z());
    }
    if (crossed) masks = writer.masksOf(block);
    if (!visit(freeWord(masks, lx), voxelBit(ly, lz))) return false;
  }
  return true;
}

// The same voxels as marchFromOrigin(origin_m, end_m, ...), visited in reverse order: from the one
// before the end's voxel back to the origin's.
template <typename Visit>
bool marchFromEnd(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& end_m, double voxel_size_m, BatchUpdates& writer,
                  Visit visit) {
  const RayWalk w(origin_m, end_m, voxel_size_m);
  const long steps = w.steps();
  if (steps == 0) return true;
  constexpr double kNever = -std::numeric_limits<double>::infinity();
  // The face behind on each axis (the one the walk from the origin crossed to get here), the t of
  // crossing it, and the steps left on the axis.
  double bx = w.key_end.x() + (w.step[0] < 0), by = w.key_end.y() + (w.step[1] < 0), bz = w.key_end.z() + (w.step[2] < 0);
  long nx = w.count[0], ny = w.count[1], nz = w.count[2];
  double tx = nx > 0 ? w.faceT(0, bx) : kNever, ty = ny > 0 ? w.faceT(1, by) : kNever,
         tz = nz > 0 ? w.faceT(2, bz) : kNever;
  const double ax = w.a[0], ay = w.a[1], az = w.a[2], cx = w.c[0], cy = w.c[1], cz = w.c[2];
  const int sx = w.step[0], sy = w.step[1], sz = w.step[2];
  int lx = w.key_end.x() & 7, ly = w.key_end.y() & 7, lz = w.key_end.z() & 7;
  BlockIndex block = blockOf(w.key_end);
  BlockMasks* masks = nullptr;
  bool crossed = true;  // the end voxel's block is looked up only if a voxel of it is visited
  for (long n = 1; n <= steps; ++n) {
    // The latest crossing first; ties to the lowest axis (the reverse of marchFromOrigin's order).
    bool wrapped;
    if (tx >= ty && tx >= tz) {
      wrapped = stepAcrossFace(lx, bx, tx, nx, -sx, ax, cx, kNever, block.x());
    } else if (ty >= tz) {
      wrapped = stepAcrossFace(ly, by, ty, ny, -sy, ay, cy, kNever, block.y());
    } else {
      wrapped = stepAcrossFace(lz, bz, tz, nz, -sz, az, cz, kNever, block.z());
    }
    crossed = crossed || wrapped;
    if (crossed) {
      masks = writer.masksOf(block);
      crossed = false;
    }
    if (!visit(freeWord(masks, lx), voxelBit(ly, lz))) return false;
  }
  return true;
}

// Visitors. Whole rays: every voxel is free.
struct CarveAll {
  bool operator()(uint64_t* word, uint64_t bit) const {
    *word |= bit;
    return true;
  }
};
// From the end back to the origin (marchFromEnd), until stop_run voxels in a row were already
// carved by earlier rays of the chunk: from there on they have carved (nearly) the same path.
struct CarveUntilRun {
  int stop_run;
  int run = 0;
  bool operator()(uint64_t* word, uint64_t bit) {
    // Without a branch on "already carved": it alternates irregularly along a ray.
    const int carved = (*word & bit) != 0;
    *word |= bit;
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
        marchFromOrigin(origin, stop, voxel_size_m, writer, CarveAll{});
      } else {
        marchFromEnd(origin, stop, voxel_size_m, writer, CarveUntilRun{stop_run});
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
