// frame_codec.h: the bytes of one stored frame (frame_store.h): the frame's points, rounded in its
// camera's frame, and the voxel updates its integration made, each section a zstd frame of its
// own (io/compression/zstd_block.h) so that a replay of the updates never decompresses the points.
//   points: quantised camera-frame points q = round(p_cam / quantum) (int32 per axis), as zigzag
//     LEB128 deltas from the previous point (neighbouring pixels: mostly 1-2 bytes per axis), then RGB.
//   updates: three kinds of parts, each compressed on its own, so that a reader decompresses only what it
//     needs: the index (touched blocks in ascending packed order, BatchUpdates' order, as LEB128
//     deltas of their packed keys, and the compressed size of each mask group), the colours (the hit
//     voxels' mean colours: zigzag deltas of their voxel index, RGB), and the mask groups (the free
//     and hit masks of 128 consecutive blocks each, every word a tag byte, none / all of its voxels /
//     literal, the literal's 8 bytes after its tag). A correction's moved frame needs the index
//     only (its old blocks), a replay the groups and colours of the blocks it rebuilds.
// Units: voxel indices, metres for poses, `quantum_m` for points. Threads: pure functions.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/point_batch.h"
#include "mapping/integration/batch_updates.h"

namespace cenote::mapping::history {

// A frame's points as the store keeps them.
struct FramePoints {
  std::vector<Eigen::Vector3i> quantised;      // p_cam / quantum_m, rounded
  std::vector<std::array<uint8_t, 3>> colors;  // one per point, or empty
};

// The updates of a frame's integration, restricted to nothing: every block it touched.
struct FrameUpdates {
  std::vector<uint64_t> keys;  // detail::packIndex of each touched block, ascending
  std::vector<BlockMasks> masks;
  std::vector<EndpointColor> colors;  // mean colour of each hit voxel (BatchUpdates::colors order)
  std::vector<uint64_t> others;       // decodeUpdates with `keep`: the touched blocks it left out
  std::vector<uint32_t> kept_at;      // decodeUpdates with `keep`: each kept block's index in `keep`

  // Copies a finished BatchUpdates.
  static FrameUpdates of(const BatchUpdates& updates);
};

// The stored coordinate of p_m: llround(p_m / quantum_m), halves away from zero, without
// llround's library call (it was a tenth of storing a frame). The conversion truncates, the
// remainder x - trunc(x) is exact (Sterbenz), and a remainder of at least one half rounds away
// from zero; quotients of 2^52 or more are integers already and take llround itself.
inline int quantisedCoordinate(double p_m, double quantum_m) {
  const double x = p_m / quantum_m;
  if (!(std::fabs(x) < 0x1p52)) return static_cast<int>(std::llround(x));
  const int64_t t = static_cast<int64_t>(x);
  const double rest = x - static_cast<double>(t);
  return static_cast<int>(t + (rest >= 0.5) - (rest <= -0.5));
}

// The world point of stored point `q` seen from T_world_cam: the one rule of the first integration
// and of every move, so that a moved frame's points are the floats a first integration at its new
// pose would see.
inline Eigen::Vector3f toWorld(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3i& q, double quantum_m) {
  return (T_world_cam * (q.cast<double>() * quantum_m)).cast<float>();
}

// Encodes / decodes one section (a zstd frame at zstd's `level`; the store uses io::kZstdFastLevel).
std::string encodePoints(const FramePoints& points, int level);
std::string encodeUpdates(const FrameUpdates& updates, int level);
// @throws Error naming `where` for bytes that do not decode (a damaged file).
FramePoints decodePoints(const std::string& bytes, const std::string& where);
FrameUpdates decodeUpdates(const std::string& bytes, const std::string& where);
// decodePoints straight to world points (a moved frame): toWorld(T_world_cam, q, quantum_m) of each
// stored point into out.points and its colour into out.colors, their capacity reused, with no
// intermediate copy (`raw`: the decompressed bytes' scratch, reused too). Returns the points' box.
// @throws as decodePoints.
Eigen::AlignedBox3f decodePointsPosed(const std::string& bytes, const std::string& where,
                                      const Eigen::Isometry3d& T_world_cam, double quantum_m, std::string& raw,
                                      PointBatch& out);
// Only the blocks whose packed keys `keep` lists (ascending), with their masks and colours; the
// others' keys go to `others` (a replay needs the masks of the blocks it rebuilds only; an empty
// `keep`: the keys alone). Both lists are merged in one pass, with no lookup per block.
FrameUpdates decodeUpdates(const std::string& bytes, const std::string& where, std::span<const uint64_t> keep);

}  // namespace cenote::mapping::history
