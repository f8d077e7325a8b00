#include "mapping/integration/batch_updates.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

namespace cenote::mapping {
namespace {

// Occupied wins in every block's masks (free &= ~hit); returns the set bits of both, i.e. the
// voxels updated. The x86-64 baseline has no POPCNT instruction (__builtin_popcountll is then a
// call into libgcc per word): a clone for CPUs with it, chosen once at load time (ifunc). Not
// under ThreadSanitizer: the loader runs the ifunc's resolver before the sanitizer's runtime is
// up, and the instrumented resolver crashes the program at start (make tsan-test).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__SANITIZE_THREAD__)
[[gnu::target_clones("popcnt", "default")]]
#endif
uint64_t
resolveMasks(BlockMasks* masks, size_t n) {
  uint64_t updated = 0;
  for (size_t b = 0; b < n; ++b) {
    BlockMasks& m = masks[b];
    for (int w = 0; w < 8; ++w) {
      m.free[w] &= ~m.hit[w];
      updated += static_cast<uint64_t>(__builtin_popcountll(m.free[w] | m.hit[w]));
    }
  }
  return updated;
}

}  // namespace

void BatchUpdates::clearMasks() {
  releaseWindow();
  table_.clear();
  masks_.clear();
}

void BatchUpdates::releaseWindow() {
  // Only the window's cells of this build's blocks were set: back to kNone, the rest already is.
  for (uint32_t b = 0; b < table_.size(); ++b) {
    const BlockIndex block = detail::unpackIndex(table_.keyOf(b));
    const uint32_t ix = static_cast<uint32_t>(block.x() - window_min_.x());
    const uint32_t iy = static_cast<uint32_t>(block.y() - window_min_.y());
    const uint32_t iz = static_cast<uint32_t>(block.z() - window_min_.z());
    if (ix < window_size_[0] && iy < window_size_[1] && iz < window_size_[2]) {
      window_[(static_cast<size_t>(ix) * window_size_[1] + iy) * window_size_[2] + iz] = detail::BlockTable::kNone;
    }
  }
  window_size_ = {0, 0, 0};
}

void BatchUpdates::setWindow(const VoxelBox& blocks) {
  releaseWindow();
  if (blocks.isEmpty()) return;
  const Eigen::Vector3i extent = blocks.max - blocks.min + Eigen::Vector3i::Ones();
  const size_t cells = static_cast<size_t>(extent.x()) * extent.y() * extent.z();
  if (cells > kMaxWindowCells) return;
  if (window_.size() < cells) window_.resize(cells, detail::BlockTable::kNone);
  window_min_ = blocks.min;
  window_size_ = {static_cast<uint32_t>(extent.x()), static_cast<uint32_t>(extent.y()), static_cast<uint32_t>(extent.z())};
}

uint32_t BatchUpdates::insert(const BlockIndex& b) {
  bool inserted;
  const uint32_t slot = table_.findOrInsert(detail::packIndex(b), inserted);
  if (inserted) masks_.emplace_back();
  return slot;
}

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
  releaseWindow();  // each window indexes its own table's blocks
  other.releaseWindow();
  std::swap(table_, other.table_);
  masks_.swap(other.masks_);
}

void BatchUpdates::finish(const EndpointSet& endpoints, bool colored) {
  finishMasks();
  colors_.clear();
  if (colored) finishColors(endpoints);
}

void BatchUpdates::finishMasks() {
  num_updated_ = resolveMasks(masks_.data(), masks_.size());
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
