#include "mapping/integration/batch_updates.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

namespace cenote::mapping {

void BatchUpdates::unite(const BatchUpdates& other) {
  for (uint32_t b = 0; b < other.table_.size(); ++b) {
    bool inserted;
    const uint32_t slot = table_.findOrInsert(other.table_.keyOf(b), inserted);
    if (inserted) masks_.emplace_back();
    for (int w = 0; w < 8; ++w) {
      masks_[slot].free[w] |= other.masks_[b].free[w];
      masks_[slot].hit[w] |= other.masks_[b].hit[w];
    }
  }
}

void BatchUpdates::swapMasks(BatchUpdates& other) {
  std::swap(table_, other.table_);
  masks_.swap(other.masks_);
}

void BatchUpdates::finish(const EndpointSet& endpoints, bool colored) {
  finishMasks();
  colors_.clear();
  if (colored) finishColors(endpoints);
}

void BatchUpdates::finishMasks() {
  for (BlockMasks& m : masks_) {
    for (int w = 0; w < 8; ++w) m.free[w] &= ~m.hit[w];
  }
  order_.resize(masks_.size());
  std::iota(order_.begin(), order_.end(), 0u);
  std::sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) { return table_.keyOf(a) < table_.keyOf(b); });
  blocks_.resize(order_.size());
  for (size_t i = 0; i < order_.size(); ++i) blocks_[i] = detail::unpackIndex(table_.keyOf(order_[i]));
}

void BatchUpdates::finishColors(const EndpointSet& endpoints) {
  // Endpoints come in point order, so neighbours often share a block (about 3 in a row on the
  // bench frames): its masks are looked up once per run (null: a block without updates, i.e. an
  // endpoint beyond range carving nothing there).
  BlockIndex block(std::numeric_limits<int>::min(), 0, 0);  // beyond any map: the first endpoint looks up
  const BlockMasks* masks = nullptr;
  for (size_t i = 0; i < endpoints.voxels().size(); ++i) {
    const VoxelIndex& ijk = endpoints.voxels()[i];
    const BlockIndex b = blockOf(ijk);
    if (b != block) {
      const uint32_t slot = table_.find(detail::packIndex(b));
      masks = slot == detail::BlockTable::kNone ? nullptr : &masks_[slot];
      block = b;
    }
    if (masks != nullptr && masks->isHit(offsetInBlock(ijk))) colors_.push_back(endpoints.meanColor(i));
  }
}

}  // namespace cenote::mapping
