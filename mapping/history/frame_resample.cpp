#include "mapping/history/frame_resample.h"

#include <algorithm>
#include <cmath>

#include "mapping/detail/block_table.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping::history {
namespace {

// A voxel is free only when the old voxel this far further along its ray is free too (see the
// header: without it the bench's map had 4x the march's occupied voxels made free).
constexpr double kGuardVoxels = 1.0;

// A rigid move in voxel units: p_to = R * p_from + t, p in voxels (a voxel's centre is ijk + 0.5).
struct VoxelMove {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  VoxelMove(const Eigen::Isometry3d& T, double voxel_size_m) : R(T.linear()), t(T.translation() / voxel_size_m) {}
  // The voxel holding the moved centre of voxel ijk.
  VoxelIndex voxelOfCentre(const VoxelIndex& ijk) const {
    const Eigen::Vector3d p = R * voxelCentre(ijk, 1.0) + t;
    return {floorToInt(p.x()), floorToInt(p.y()), floorToInt(p.z())};
  }
};

bool blockInMapRange(const BlockIndex& block) {
  return inMapRange(block * kBlockSide) && inMapRange(block * kBlockSide + VoxelIndex::Constant(kBlockSide - 1));
}

bool anyBit(const std::array<uint64_t, 8>& mask) {
  return std::any_of(mask.begin(), mask.end(), [](uint64_t w) { return w != 0; });
}

// The blocks being written, by packed key, in the order first touched.
class NewBlocks {
 public:
  uint32_t slotOf(uint64_t key) {
    bool inserted = false;
    const uint32_t slot = table_.findOrInsert(key, inserted);
    if (inserted) masks_.emplace_back();
    return slot;
  }
  uint32_t find(uint64_t key) const { return table_.find(key); }
  BlockMasks& masks(uint32_t slot) { return masks_[slot]; }
  size_t size() const { return masks_.size(); }
  uint64_t keyOf(uint32_t slot) const { return table_.keyOf(slot); }

 private:
  detail::BlockTable table_;
  std::vector<BlockMasks> masks_;
};

// Old free bits by position, remembering the last old block looked up (most of a new block's
// samples fall in one or two old blocks).
class OldBlockCache {
 public:
  OldBlockCache(const detail::BlockTable& table, const FrameUpdates& updates) : table_(table), updates_(updates) {}
  // Whether the old voxel holding p (in voxels) is free.
  bool isFree(const Eigen::Vector3d& p) {
    const VoxelIndex old(floorToInt(p.x()), floorToInt(p.y()), floorToInt(p.z()));
    const uint64_t key = detail::packIndex(blockOf(old));
    if (key != last_key_) {
      last_key_ = key;
      const uint32_t slot = table_.find(key);
      last_ = slot == detail::BlockTable::kNone ? nullptr : &updates_.masks[slot];
    }
    if (last_ == nullptr) return false;
    const int o = offsetInBlock(old);
    return (last_->free[o >> 6] >> (o & 63)) & 1;
  }

 private:
  const detail::BlockTable& table_;
  const FrameUpdates& updates_;
  uint64_t last_key_ = detail::BlockTable::kEmpty;
  const BlockMasks* last_ = nullptr;
};

// The new blocks whose voxel centres may fall, moved back, inside old block `block`: those that the
// box of its moved cube (the corners of its 8^3 voxels, in voxel units) reaches.
template <typename Visit>
void forBlocksReached(const VoxelMove& forward, const BlockIndex& block, Visit visit) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((block.x() + (c & 1)) * kBlockSide, (block.y() + ((c >> 1) & 1)) * kBlockSide,
                                 (block.z() + ((c >> 2) & 1)) * kBlockSide);
    const Eigen::Vector3d p = forward.R * corner + forward.t;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Voxels whose centre ijk + 0.5 lies in [lo, hi]: ijk in [ceil(lo - 0.5), floor(hi - 0.5)].
  BlockIndex first, last;
  for (int k = 0; k < 3; ++k) {
    first[k] = floorToInt(std::ceil(lo[k] - 0.5)) >> kBlockShift;
    last[k] = floorToInt(hi[k] - 0.5) >> kBlockShift;
  }
  for (int x = first.x(); x <= last.x(); ++x) {
    for (int y = first.y(); y <= last.y(); ++y) {
      for (int z = first.z(); z <= last.z(); ++z) visit(BlockIndex(x, y, z));
    }
  }
}

}  // namespace

FrameUpdates resampleUpdates(const FrameUpdates& updates, const Eigen::Isometry3d& T_new_old,
                             const Eigen::Vector3d& origin_new_m, double voxel_size_m) {
  const VoxelMove forward(T_new_old, voxel_size_m);
  const Eigen::Vector3d origin = origin_new_m / voxel_size_m;
  // A move by whole voxels without rotation (none, most often: a frame moved back to the pose it
  // was marched at) maps voxels onto voxels: the pull is exact and needs no guard.
  const bool whole_voxels = forward.R.isIdentity(1e-12) &&
                            (forward.t - forward.t.array().round().matrix()).cwiseAbs().maxCoeff() < 1e-9;
  const double guard_voxels = whole_voxels ? 0.0 : kGuardVoxels;
  const VoxelMove back(T_new_old.inverse(), voxel_size_m);
  detail::BlockTable old_blocks;  // slot = index in updates.keys
  for (uint64_t key : updates.keys) {
    bool inserted = false;
    old_blocks.findOrInsert(key, inserted);
  }

  // Free: every voxel of every new block an old block with a free voxel reaches, pulled from the
  // old voxel under its centre, guarded by the old voxel a step further along its ray.
  NewBlocks out;
  for (size_t b = 0; b < updates.keys.size(); ++b) {
    if (!anyBit(updates.masks[b].free)) continue;
    forBlocksReached(forward, detail::unpackIndex(updates.keys[b]), [&](const BlockIndex& block) {
      if (blockInMapRange(block)) out.slotOf(detail::packIndex(block));
    });
  }
  const size_t free_blocks = out.size();
  for (uint32_t slot = 0; slot < free_blocks; ++slot) {
    const BlockIndex block = detail::unpackIndex(out.keyOf(slot));
    const Eigen::Vector3d p0 = back.R * voxelCentre(block * kBlockSide, 1.0) + back.t;
    std::array<uint64_t, 8>& free = out.masks(slot).free;
    // The step to the guard sample, in old voxels: kGuardVoxels along the ray through the block's
    // centre (within a block the rays' directions differ little; the blocks around the origin,
    // where they differ most, have no guard).
    const Eigen::Vector3d ray = (block * kBlockSide).cast<double>() + Eigen::Vector3d::Constant(kBlockSide / 2.0) - origin;
    const double range = ray.norm();
    const Eigen::Vector3d guard = range > kBlockSide ? Eigen::Vector3d(back.R * (ray * (guard_voxels / range)))
                                                     : Eigen::Vector3d::Zero();
    OldBlockCache at(old_blocks, updates), further(old_blocks, updates);
    for (int i = 0; i < kBlockSide; ++i) {
      const Eigen::Vector3d pi = p0 + back.R.col(0) * i;
      for (int j = 0; j < kBlockSide; ++j) {
        const Eigen::Vector3d pij = pi + back.R.col(1) * j;
        for (int k = 0; k < kBlockSide; ++k) {
          const Eigen::Vector3d p = pij + back.R.col(2) * k;
          if (at.isFree(p) && further.isFree(p + guard)) {
            const int n = (i << 6) | (j << 3) | k;
            free[n >> 6] |= 1ull << (n & 63);
          }
        }
      }
    }
  }

  // Hits: each old hit voxel's centre, moved; colours with them, one per new voxel.
  for (size_t b = 0; b < updates.keys.size(); ++b) {
    const BlockIndex block = detail::unpackIndex(updates.keys[b]);
    const std::array<uint64_t, 8>& hit = updates.masks[b].hit;
    for (int w = 0; w < 8; ++w) {
      for (uint64_t bits = hit[w]; bits != 0; bits &= bits - 1) {
        const VoxelIndex moved = forward.voxelOfCentre(voxelOfOffset(block, w * 64 + __builtin_ctzll(bits)));
        if (!inMapRange(moved)) continue;
        const int o = offsetInBlock(moved);
        out.masks(out.slotOf(detail::packIndex(blockOf(moved)))).hit[o >> 6] |= 1ull << (o & 63);
      }
    }
  }
  FrameUpdates result;
  std::vector<std::array<uint64_t, 8>> coloured(out.size());
  for (const EndpointColor& c : updates.colors) {
    const VoxelIndex moved = forward.voxelOfCentre(c.ijk);
    const uint32_t slot = out.find(detail::packIndex(blockOf(moved)));
    const int o = offsetInBlock(moved);
    if (slot == detail::BlockTable::kNone || !out.masks(slot).isHit(o)) continue;  // a colour of no hit voxel
    uint64_t& word = coloured[slot][o >> 6];
    if ((word >> (o & 63)) & 1) continue;
    word |= 1ull << (o & 63);
    result.colors.push_back({moved, c.rgb});
  }

  // Occupied wins; blocks left with no bit are not touched.
  std::vector<uint32_t> slots;
  for (uint32_t slot = 0; slot < out.size(); ++slot) {
    BlockMasks& m = out.masks(slot);
    for (int w = 0; w < 8; ++w) m.free[w] &= ~m.hit[w];
    if (anyBit(m.free) || anyBit(m.hit)) slots.push_back(slot);
  }
  std::sort(slots.begin(), slots.end(), [&](uint32_t a, uint32_t b) { return out.keyOf(a) < out.keyOf(b); });
  result.keys.reserve(slots.size());
  result.masks.reserve(slots.size());
  for (uint32_t slot : slots) {
    result.keys.push_back(out.keyOf(slot));
    result.masks.push_back(out.masks(slot));
  }
  return result;
}

}  // namespace cenote::mapping::history
