#include "mapping/integration/ray_batch.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "mapping/integration/point_voxels.h"
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
// key_origin and key_end are the voxels of origin_m and end_m (toVoxel), which the caller knows:
// the origin's is the same for every ray of a batch, and an endpoint voxel's centre lies in it.
struct RayWalk {
  VoxelIndex key_origin, key_end;
  int step[3];        // +-1 along the ray, 0 for an axis it never steps on
  long count[3];      // steps on each axis from the origin's voxel to the end's
  double a[3], c[3];  // t of face b on axis i: b a[i] - c[i]

  RayWalk(const Eigen::Vector3d& origin_m, const VoxelIndex& origin_key, const Eigen::Vector3d& end_m,
          const VoxelIndex& end_key, double s)
      : key_origin(origin_key), key_end(end_key) {
    // Both quotients of each axis in two packed divisions (IEEE division rounds each lane as the
    // scalar one does: the same bits).
    const Eigen::Array4d d(end_m.x() - origin_m.x(), end_m.y() - origin_m.y(), end_m.z() - origin_m.z(), 1.0);
    const Eigen::Array4d a4 = Eigen::Array4d::Constant(s) / d;
    const Eigen::Array4d c4 = Eigen::Array4d(origin_m.x(), origin_m.y(), origin_m.z(), 0.0) / d;
    for (int i = 0; i < 3; ++i) {
      const long n = static_cast<long>(key_end[i]) - key_origin[i];
      step[i] = n > 0 ? 1 : (n < 0 ? -1 : 0);
      count[i] = n < 0 ? -n : n;
      // Distinct voxels on an axis mean distinct coordinates: d[i] != 0 where count[i] > 0.
      a[i] = count[i] > 0 ? a4[i] : 0.0;
      c[i] = count[i] > 0 ? c4[i] : 0.0;
    }
  }
  long steps() const { return count[0] + count[1] + count[2]; }
  double faceT(int i, double b) const { return b * a[i] - c[i]; }
};

// The walk of one ray in one direction, with the direction's signs on each axis (SX, SY, SZ: +-1,
// the walk's own: from the end back to the origin they are the ray's negated) as constants: one
// instance per octant keeps the whole state in registers, and each step is a few instructions.
// kFromEnd false: the voxels of the ray from the origin's voxel up to the end's, exclusive
// (OctoMap's free-space rule; nothing when both share a voxel), in order; crossings in order of
// increasing t, ties to the highest axis. kFromEnd true: the same voxels in reverse order, from the
// one before the end's voxel back to the origin's (decreasing t, ties to the lowest axis).
// visit(word, bit) on each voxel (its word of its block's free mask and its bit in it); false
// stops the walk. Returns the voxels visited (`steps` when the visitor did not stop the walk). A
// block's masks are looked up (and created) only when a voxel of it is about to be visited, after
// the walk entered it. The visitor is taken by value: its state stays in registers. Flattened: its
// lambdas and masksOf inline into the loop (16 instances exhaust the compiler's inlining budget
// otherwise).
template <int SX, int SY, int SZ, bool kFromEnd, typename Visit>
[[gnu::flatten]] long walkOctant(const RayWalk& w, long steps, BatchUpdates& writer, Visit visit) {
  constexpr double kNever = kFromEnd ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  const VoxelIndex& start = kFromEnd ? w.key_end : w.key_origin;
  // The next face on each axis (from the end, the face behind, which the walk from the origin
  // crossed to get there) is always the voxel's coordinate + (S > 0): its index, converted exactly
  // to a double where its t is taken. Then the t of crossing it. (Faces kept as doubles, +-1.0 a
  // step, take more instructions: no double register survives masksOf's call of insert(), so GCC
  // keeps them on the stack, a load and a store per step; 203 M -> 211 M in map_bench's walk.)
  constexpr int kx = SX > 0, ky = SY > 0, kz = SZ > 0;
  const VoxelIndex& s0 = start;
  const double bx = s0.x() + kx, by = s0.y() + ky, bz = s0.z() + kz;
  // An axis has no face left once its coordinate reached the other end's: the test against that
  // (a constant of the ray) takes no register in the loop, as a count of steps left would.
  const VoxelIndex& last = kFromEnd ? w.key_origin : w.key_end;
  const int lx = last.x(), ly = last.y(), lz = last.z();
  double tx = w.count[0] > 0 ? w.faceT(0, bx) : kNever, ty = w.count[1] > 0 ? w.faceT(1, by) : kNever,
         tz = w.count[2] > 0 ? w.faceT(2, bz) : kNever;
  const double ax = w.a[0], ay = w.a[1], az = w.a[2], cx = w.c[0], cy = w.c[1], cz = w.c[2];
  // The voxel (global coordinates), its word and bit (kept in step within a block, looked up
  // afresh when the walk crosses into another).
  int x = start.x(), y = start.y(), z = start.z();
  uintptr_t word = 0;  // an address: stepping it out of its block's words is no pointer arithmetic
  uint64_t bit = 0;
  auto lookUp = [&] {
    BlockMasks* masks = writer.masksOf(BlockIndex(x >> kBlockShift, y >> kBlockShift, z >> kBlockShift));
    word = reinterpret_cast<uintptr_t>(masks->free.data() + (x & 7));
    bit = 1ull << (((y & 7) << 3) | (z & 7));
  };
  // One step across the next face; true when it entered another block: a coordinate that steps
  // onto a multiple of 8 (SX > 0) or off one (SX < 0).
  auto advance = [&] {
    if (kFromEnd ? (tx >= ty && tx >= tz) : (tx < ty && tx < tz)) {
      x += SX;
      tx = x != lx ? static_cast<double>(x + kx) * ax - cx : kNever;
      word += SX * static_cast<int>(sizeof(uint64_t));
      return (x & 7) == (SX > 0 ? 0 : 7);
    }
    if (kFromEnd ? ty >= tz : ty < tz) {
      y += SY;
      ty = y != ly ? static_cast<double>(y + ky) * ay - cy : kNever;
      bit = SY > 0 ? bit << 8 : bit >> 8;
      return (y & 7) == (SY > 0 ? 0 : 7);
    }
    z += SZ;
    tz = z != lz ? static_cast<double>(z + kz) * az - cz : kNever;
    bit = SZ > 0 ? bit << 1 : bit >> 1;
    return (z & 7) == (SZ > 0 ? 0 : 7);
  };
  auto visitHere = [&] { return visit(reinterpret_cast<uint64_t*>(word), bit); };
  // From the origin its voxel is the first, and the last step enters the end voxel, which is not
  // visited; from the end the first voxel is the one after the first step (so the end voxel's
  // block is looked up only if a voxel of it is visited). Then steps - 1 steps either way.
  if (kFromEnd) advance();
  lookUp();
  if (!visitHere()) return 1;
  for (long n = steps - 1; n > 0; --n) {
    if (advance()) lookUp();
    if (!visitHere()) return steps - n + 1;
  }
  return steps;
}

// walkOctant for the ray's octant: from the origin (kFromEnd false) or from the end. An axis the
// ray never steps on takes +1 (its t is never the next). Returns the voxels visited.
template <bool kFromEnd, typename Visit>
long march(const RayWalk& w, BatchUpdates& writer, Visit visit) {
  const long steps = w.steps();
  if (steps == 0) return 0;
  const int sign = kFromEnd ? -1 : 1;
  const int octant = (sign * w.step[0] < 0) << 2 | (sign * w.step[1] < 0) << 1 | (sign * w.step[2] < 0);
  switch (octant) {
    case 0: return walkOctant<1, 1, 1, kFromEnd>(w, steps, writer, visit);
    case 1: return walkOctant<1, 1, -1, kFromEnd>(w, steps, writer, visit);
    case 2: return walkOctant<1, -1, 1, kFromEnd>(w, steps, writer, visit);
    case 3: return walkOctant<1, -1, -1, kFromEnd>(w, steps, writer, visit);
    case 4: return walkOctant<-1, 1, 1, kFromEnd>(w, steps, writer, visit);
    case 5: return walkOctant<-1, 1, -1, kFromEnd>(w, steps, writer, visit);
    case 6: return walkOctant<-1, -1, 1, kFromEnd>(w, steps, writer, visit);
    default: return walkOctant<-1, -1, -1, kFromEnd>(w, steps, writer, visit);
  }
}

// Visitors. Whole rays: every voxel is free.
struct CarveAll {
  bool operator()(uint64_t* word, uint64_t bit) const {
    *word |= bit;
    return true;
  }
};
// From the end back to the origin (march<true>), until stop_run voxels in a row were already
// carved by earlier rays of the chunk: from there on they have carved (nearly) the same path.
struct CarveUntilRun {
  int stop_run;
  int run = 0;
  bool operator()(uint64_t* word, uint64_t bit) {
    // Without a branch on "already carved": it alternates irregularly along a ray. (A conditional
    // move instead takes 4 % fewer instructions but 8 % more CPU time on the bench.)
    const int carved = (*word & bit) != 0;
    *word |= bit;
    run = (run + 1) & -carved;
    return run < stop_run;
  }
};

// The order in which early stopping marches a chunk's rays: kSpreadPasses passes over its
// endpoints (which come in point order: image rows), pass p taking every kSpreadPasses-th one from
// offset kSpreadOffsets[p] (the bit reversal of p: 0, 8, 4, 12, 2, ...), so that each pass falls
// halfway between the rays of the passes before. In image order a ray's neighbours in the rows
// above it have carved only the half of its surroundings above it, and it keeps finding voxels
// they left uncarved, a few steps apart, all the way to the camera (the run of 16 carved voxels
// that stopped it came late: 97 steps a ray on bench/map_bench's frames, 21 of them new). In
// passes, the rays marched before it lie on all sides of it, and it meets the carved path sooner:
// with a run of 32, 2.34 M steps a frame where image order with 16 took 3.08 M, for fewer voxels
// left unknown. Consecutive rays of a pass are 16 endpoints apart, so they cross nearly the same
// blocks and their walks branch alike: 5 % less CPU time than a Weyl sequence over the whole chunk
// (i phi mod n), which marches 1 % more steps.
constexpr size_t kSpreadPasses = 16;
constexpr std::array<size_t, kSpreadPasses> kSpreadOffsets = {0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15};

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
  const VoxelIndex key_origin = toVoxel(origin, voxel_size_m);
  const bool limited = max_range_m > 0.0;
  const size_t n = batch.points.size();
  updates_.clearMasks();
  endpoints_.clear();
  bool first_done = false;  // a chunk's masks are in updates_
  int next_merge = 0;       // the first chunk whose colours are not yet in endpoints_
  for (int c = 0; c < num_chunks; ++c) chunks_[c].done = false;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int c = 0; c < num_chunks; ++c) {
    Chunk& chunk = chunks_[c];
    chunk.updates.clearMasks();
    chunk.endpoints.clear();
    const size_t begin = n * c / num_chunks, count = n * (c + 1) / num_chunks - begin;
    chunk.voxels.resize(count);
    pointVoxels(batch.points.data() + begin, count, voxel_size_m, chunk.voxels.data());
    for (size_t i = 0; i < count; ++i) {
      chunk.endpoints.add(chunk.voxels[i], batch.hasColor() ? batch.colors[begin + i].data() : nullptr);
    }
    BatchUpdates& writer = chunk.updates;
    // Every voxel a ray of the chunk visits lies in the box of the origin's and the endpoints'
    // voxels (a stop short of the maximum range lies between them): their blocks are the window.
    VoxelBox window{blockOf(key_origin), blockOf(key_origin)};
    for (const VoxelIndex& endpoint : chunk.endpoints.voxels()) window.extend(blockOf(endpoint));
    writer.setWindow(window);
    // Early stop: in passes (whole rays: in point order, whose neighbouring rays share blocks).
    const std::vector<VoxelIndex>& endpoints = chunk.endpoints.voxels();
    const size_t passes = exact ? 1 : kSpreadPasses;
    size_t steps = 0;
    for (size_t pass = 0; pass < passes; ++pass) {
      for (size_t e = kSpreadOffsets[pass]; e < endpoints.size(); e += passes) {
        const VoxelIndex& endpoint = endpoints[e];
        const Eigen::Vector3d end = voxelCentre(endpoint, voxel_size_m);
        const Eigen::Vector3d ray = end - origin;
        const double range = ray.norm();
        const bool in_range = !limited || range <= max_range_m;
        // An endpoint voxel's centre lies in that voxel: toVoxel(end) is the endpoint.
        const Eigen::Vector3d stop = in_range ? end : Eigen::Vector3d(origin + ray * (max_range_m / range));
        const RayWalk walk(origin, key_origin, stop, in_range ? endpoint : toVoxel(stop, voxel_size_m), voxel_size_m);
        steps += static_cast<size_t>(exact ? march<false>(walk, writer, CarveAll{})
                                           : march<true>(walk, writer, CarveUntilRun{stop_run}));
        if (in_range) writer.setHit(endpoint);
      }
    }
    chunk.steps = steps;
    // 2. The union of the chunks' masks, as each chunk ends: the other threads march on meanwhile.
    // Any order gives the same union (finish() sorts the blocks). The first chunk's masks are
    // taken over, not copied. 3. The endpoints' colour sums (an endpoint voxel may span two
    // bands), merged in chunk order, each chunk as soon as those before it are: the colours' order,
    // and so the order in which the map's colour store meets their blocks, is the same for any
    // thread count.
#pragma omp critical(cenote_ray_batch_union)
    {
      if (first_done) {
        updates_.unite(writer);
      } else {
        updates_.swapMasks(writer);
        first_done = true;
      }
      chunk.done = true;
      for (; next_merge < num_chunks && chunks_[next_merge].done; ++next_merge) {
        if (batch.hasColor()) endpoints_.merge(chunks_[next_merge].endpoints);
      }
    }
  }
  num_rays_ = 0;
  num_steps_ = 0;
  for (int c = 0; c < num_chunks; ++c) {
    num_rays_ += chunks_[c].endpoints.voxels().size();
    num_steps_ += chunks_[c].steps;
  }

  // Mean colours of the hit voxels: finish() keeps those whose hit bit is set, i.e. the endpoints
  // within range.
  updates_.finish(endpoints_, batch.hasColor());
}

}  // namespace cenote::mapping
