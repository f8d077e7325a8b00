// batch_updates.h: the voxel updates of one integration batch, as OccupancyMap publishes them:
// for every touched block a free mask and a hit mask (each voxel updated at most once, occupied
// wins), blocks in ascending packed order, and the mean colour of every hit voxel. RayBatch and
// ProjectiveBatch each build one (and hand it out read-only to OccupancyMap::publish); RayBatch's
// chunks also fill one each.
// Units: voxel indices. Threads: one owner.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "mapping/detail/block_table.h"
#include "mapping/integration/endpoint_set.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping {

struct BlockMasks {
  std::array<uint64_t, 8> free{};  // bit offsetInBlock(ijk): crossed by a ray (not hit)
  std::array<uint64_t, 8> hit{};   // bit offsetInBlock(ijk): holds an endpoint within range
  bool isHit(int offset) const { return (hit[offset >> 6] >> (offset & 63)) & 1; }
};

class BatchUpdates {
 public:
  // After finish(): touched blocks in ascending packed order, with their masks.
  size_t numBlocks() const { return blocks_.size(); }
  const BlockIndex& block(size_t i) const { return blocks_[i]; }
  const BlockMasks& masks(size_t i) const { return masks_[order_[i]]; }
  // After finish(): the voxels updated (set bits of all free and hit masks).
  uint64_t numUpdated() const { return num_updated_; }
  // After finish(): mean colour of every hit voxel (empty for an uncoloured batch).
  const std::vector<EndpointColor>& colors() const { return colors_; }

  // Building. Forgets every block (capacity kept) and the window.
  void clearMasks();
  // Optional, after clearMasks(): a dense index of the blocks in `blocks` (inclusive block
  // indices), through which masksOf() finds them without hashing (a ray crosses into another block
  // about every 8 steps; the hash was a sixth of the march's instructions). Blocks outside it are
  // still found, through the hash table. A box of more than kMaxWindowCells blocks sets none.
  // Nothing else changes: blocks get the same slots in the same order with or without it.
  void setWindow(const VoxelBox& blocks);
  static constexpr size_t kMaxWindowCells = size_t{1} << 18;  // 1 MiB of slots
  // The masks of block b, created empty when new. The pointer is valid until the next call.
  // Always inlined: the march calls it every 8 steps or so, from 16 instances of its walk.
  [[gnu::always_inline]] BlockMasks* masksOf(const BlockIndex& b) {
    const uint32_t ix = static_cast<uint32_t>(b.x() - window_min_.x());
    const uint32_t iy = static_cast<uint32_t>(b.y() - window_min_.y());
    const uint32_t iz = static_cast<uint32_t>(b.z() - window_min_.z());
    if (ix < window_size_[0] && iy < window_size_[1] && iz < window_size_[2]) {
      uint32_t& slot = window_[(static_cast<size_t>(ix) * window_size_[1] + iy) * window_size_[2] + iz];
      if (slot == detail::BlockTable::kNone) slot = insert(b);
      return &masks_[slot];
    }
    return &masks_[insert(b)];
  }
  void setHit(const VoxelIndex& ijk) {
    const int o = offsetInBlock(ijk);
    masksOf(blockOf(ijk))->hit[o >> 6] |= 1ull << (o & 63);
  }
  // ORs the masks of `other` into these.
  void unite(const BatchUpdates& other);
  // Exchanges the masks being built with those of `other` (and turns both windows off).
  void swapMasks(BatchUpdates& other);
  // Ends building: occupied wins (free &= ~hit), blocks sorted; with colored, the mean colour of
  // every endpoint voxel whose hit bit is set, in the endpoints' order (an endpoint beyond the
  // maximum range set no hit, so it records no colour either).
  void finish(const EndpointSet& endpoints, bool colored);

 private:
  void finishMasks();
  void finishColors(const EndpointSet& endpoints);
  // Sets the window's cells back to kNone and turns it off.
  void releaseWindow();
  // The slot of block b in table_ and masks_, a new empty one when b is new. Out of line (once per
  // block, or a block outside the window), so that masksOf's window path inlines into the march.
  uint32_t insert(const BlockIndex& b);

  detail::BlockTable table_;  // block -> slot in masks_
  std::vector<BlockMasks> masks_;
  std::vector<BlockIndex> blocks_;
  std::vector<uint32_t> order_;  // slots in ascending packed order
  std::vector<EndpointColor> colors_;
  uint64_t num_updated_ = 0;
  // The window (setWindow): slots of the blocks from window_min_ on, x slowest; kNone where a
  // block has none yet, and everywhere between builds. window_size_ 0: no window.
  std::vector<uint32_t> window_;
  BlockIndex window_min_ = BlockIndex::Zero();
  std::array<uint32_t, 3> window_size_{0, 0, 0};
};

}  // namespace cenote::mapping
