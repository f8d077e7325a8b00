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
  // After finish(): mean colour of every hit voxel (empty for an uncoloured batch).
  const std::vector<EndpointColor>& colors() const { return colors_; }

  // Building. Forgets every block (capacity kept).
  void clearMasks() {
    table_.clear();
    masks_.clear();
  }
  // The masks of block b, created empty when new. The pointer is valid until the next call.
  BlockMasks* masksOf(const BlockIndex& b) {
    bool inserted;
    const uint32_t slot = table_.findOrInsert(detail::packIndex(b), inserted);
    if (inserted) masks_.emplace_back();
    return &masks_[slot];
  }
  void setHit(const VoxelIndex& ijk) {
    const int o = offsetInBlock(ijk);
    masksOf(blockOf(ijk))->hit[o >> 6] |= 1ull << (o & 63);
  }
  // ORs the masks of `other` into these.
  void unite(const BatchUpdates& other);
  // Exchanges the masks being built with those of `other`.
  void swapMasks(BatchUpdates& other);
  // Ends building: occupied wins (free &= ~hit), blocks sorted; with colored, the mean colour of
  // every endpoint voxel whose hit bit is set, in the endpoints' order (an endpoint beyond the
  // maximum range set no hit, so it records no colour either).
  void finish(const EndpointSet& endpoints, bool colored);

 private:
  void finishMasks();
  void finishColors(const EndpointSet& endpoints);

  detail::BlockTable table_;  // block -> slot in masks_
  std::vector<BlockMasks> masks_;
  std::vector<BlockIndex> blocks_;
  std::vector<uint32_t> order_;  // slots in ascending packed order
  std::vector<EndpointColor> colors_;
};

}  // namespace cenote::mapping
