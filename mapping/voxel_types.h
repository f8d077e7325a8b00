// voxel_types.h: the plain value types of the map's interface: voxel and block indices, voxel
// states, axis-aligned boxes and the change record (MapDelta) that one integration returns.
// Units: metres for world coordinates; voxel indices are integers. Frame: world.
// Grid convention (the same as OctoMap's keys, without their 2^15 offset): voxel i along an axis
// covers [i * s, (i + 1) * s) for voxel size s, so its centre is (i + 0.5) * s. A block is the
// 8 x 8 x 8 voxels with the same floor(i / 8) (an OpenVDB leaf node).
// Threads: plain values.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace cenote::mapping {

using VoxelIndex = Eigen::Vector3i;
using BlockIndex = Eigen::Vector3i;

inline constexpr int kBlockShift = 3;  // 8 voxels per block side
inline constexpr int kBlockSide = 1 << kBlockShift;
inline constexpr int kBlockVoxels = kBlockSide * kBlockSide * kBlockSide;
// Voxels a map holds lie within +-kMaxVoxelIndex of 0 on each axis (52 km at 5 cm, 1 km at 1 mm):
// packed keys (detail::packIndex) hold 21 bits per axis, for a voxel (endpoint de-duplication) as
// for a block and each of its neighbours.
inline constexpr int kMaxVoxelIndex = (1 << 20) - kBlockSide;
inline bool inMapRange(const Eigen::Vector3i& ijk) {
  return (ijk.array() >= -kMaxVoxelIndex).all() && (ijk.array() <= kMaxVoxelIndex).all();
}

// Unknown: never observed. Unknown is never free.
enum class VoxelState : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

const char* toString(VoxelState state);

inline BlockIndex blockOf(const VoxelIndex& ijk) {
  return BlockIndex(ijk.x() >> kBlockShift, ijk.y() >> kBlockShift, ijk.z() >> kBlockShift);
}
// Offset of a voxel inside its block, x slowest (OpenVDB leaf order): ((x*8)+y)*8+z.
inline int offsetInBlock(const VoxelIndex& ijk) { return ((ijk.x() & 7) << 6) | ((ijk.y() & 7) << 3) | (ijk.z() & 7); }
inline VoxelIndex voxelOfOffset(const BlockIndex& block, int offset) {
  return VoxelIndex((block.x() << kBlockShift) + (offset >> 6), (block.y() << kBlockShift) + ((offset >> 3) & 7),
                    (block.z() << kBlockShift) + (offset & 7));
}

// Axis-aligned box in world metres; empty when any min > max.
struct Aabb {
  Eigen::Vector3d min_m = Eigen::Vector3d::Constant(1.0);
  Eigen::Vector3d max_m = Eigen::Vector3d::Constant(-1.0);

  bool isEmpty() const { return (min_m.array() > max_m.array()).any(); }
  void extend(const Eigen::Vector3d& p_m) {
    if (isEmpty()) {
      min_m = max_m = p_m;
    } else {
      min_m = min_m.cwiseMin(p_m);
      max_m = max_m.cwiseMax(p_m);
    }
  }
  void extend(const Aabb& other) {
    if (other.isEmpty()) return;
    extend(other.min_m);
    extend(other.max_m);
  }
  bool contains(const Eigen::Vector3d& p_m) const {
    return (p_m.array() >= min_m.array()).all() && (p_m.array() <= max_m.array()).all();
  }
};

// Inclusive box of voxel indices; empty when any min > max.
struct VoxelBox {
  VoxelIndex min = VoxelIndex::Constant(1);
  VoxelIndex max = VoxelIndex::Constant(0);
  bool isEmpty() const { return (min.array() > max.array()).any(); }
  void extend(const VoxelIndex& ijk) {
    if (isEmpty()) {
      min = max = ijk;
    } else {
      min = min.cwiseMin(ijk);
      max = max.cwiseMax(ijk);
    }
  }
  void extend(const VoxelBox& other) {
    if (other.isEmpty()) return;
    extend(other.min);
    extend(other.max);
  }
  bool contains(const VoxelIndex& ijk) const {
    return (ijk.array() >= min.array()).all() && (ijk.array() <= max.array()).all();
  }
};

// What one change of the map (integrate, clear, crop, reset) touched.
struct MapDelta {
  std::vector<BlockIndex> changed_blocks;  // blocks with at least one changed voxel, sorted, unique
  VoxelBox changed_voxels;                 // bounding box of the changed voxels
  Aabb changed_m;                          // the same box in world metres (voxel faces)
  uint64_t voxels_updated = 0;             // voxel updates applied (each voxel at most once per batch)
  uint64_t points_used = 0;                // points whose ray was cast (after range and dedup rules)
  bool isEmpty() const { return changed_blocks.empty(); }
  // Appends another delta (blocks stay sorted and unique).
  void merge(const MapDelta& other);
};

}  // namespace cenote::mapping
