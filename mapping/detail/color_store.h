// color_store.h: the colours of the map's hit voxels, stored sparsely: per 8x8x8 block (the log-odds
// grid's leaf) a 512-bit mask and the packed colours of its set bits only.
// Why not an OpenVDB Int32Grid (which the map used before): only hit voxels have a colour (about
// 5 % of the known voxels at 5 cm, a few per block), so the grid's dense 512-value leaves held
// ~40x more memory than colours (2.3 MB of the bench's 9.7 MB map). .vdb files still hold an
// Int32Grid "color" (mapping/io/map_io.cpp converts both ways).
// Values: map_impl.h packColor. Indices: voxel_types.h; voxels must lie within +-kMaxVoxelIndex on each
// axis to be set (what OccupancyMap accepts); get() reports voxels beyond as colourless.
// Threads: none; OccupancyMap guards it with its grid mutex.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "mapping/detail/block_table.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping::detail {

// Colours of one block: bit offsetInBlock(ijk) of `has`, and the packed colours of the set bits in
// ascending offset order.
struct BlockColors {
  std::array<uint64_t, 8> has{};
  std::array<uint16_t, 8> before{};  // set bits in the words before each word (one popcount per rank)
  std::vector<int32_t> packed;

  // Index in `packed` of the voxel at `offset` (whether or not it has a colour).
  size_t rank(int offset) const {
    const int w = offset >> 6;
    return before[w] + static_cast<size_t>(__builtin_popcountll(has[w] & ((1ull << (offset & 63)) - 1)));
  }
  bool get(int offset, int32_t& value) const {
    if (((has[offset >> 6] >> (offset & 63)) & 1) == 0) return false;
    value = packed[rank(offset)];
    return true;
  }
  // The colour of the voxel at `offset`, inserted as 0 when absent (inserted set to true); valid
  // until the next insertion.
  int32_t& at(int offset, bool& inserted) {
    const size_t r = rank(offset);
    const int w = offset >> 6;
    const uint64_t bit = 1ull << (offset & 63);
    inserted = (has[w] & bit) == 0;
    if (inserted) {
      has[w] |= bit;
      for (int i = w + 1; i < 8; ++i) ++before[i];
      packed.insert(packed.begin() + static_cast<std::ptrdiff_t>(r), 0);
    }
    return packed[r];
  }
  void set(int offset, int32_t value) {
    bool inserted;
    at(offset, inserted) = value;
  }
  // Removes the colours of the voxels for which remove(ijk) is true (ijk: voxelOfOffset(block, .)).
  template <typename Remove>
  void eraseIf(const BlockIndex& block, Remove&& remove) {
    size_t kept = 0, i = 0;
    for (int w = 0; w < 8; ++w) {
      before[w] = static_cast<uint16_t>(kept);
      for (uint64_t bits = has[w]; bits != 0; bits &= bits - 1, ++i) {
        const int bit = __builtin_ctzll(bits);
        if (remove(voxelOfOffset(block, w * 64 + bit))) {
          has[w] &= ~(1ull << bit);
        } else {
          packed[kept++] = packed[i];
        }
      }
    }
    packed.resize(kept);
    if (kept == 0) packed.shrink_to_fit();
  }
};

class ColorStore {
 public:
  bool get(const VoxelIndex& ijk, int32_t& packed) const {
    const BlockIndex block = blockOf(ijk);
    if (!inPackRange(block)) return false;
    const uint32_t slot = table_.find(packIndex(block));
    return slot != BlockTable::kNone && blocks_[slot].get(offsetInBlock(ijk), packed);
  }
  // The colour of a voxel, inserted as 0 when absent (inserted set to true); valid until the next
  // insertion. Precondition: inPackRange(blockOf(ijk)).
  int32_t& at(const VoxelIndex& ijk, bool& inserted) {
    const uint32_t slot = table_.findOrInsert(packIndex(blockOf(ijk)), inserted);
    if (inserted) blocks_.emplace_back();
    return blocks_[slot].at(offsetInBlock(ijk), inserted);
  }
  // Precondition: inPackRange(blockOf(ijk)).
  void set(const VoxelIndex& ijk, int32_t packed) {
    bool inserted;
    at(ijk, inserted) = packed;
  }

  // visit(ijk, packed) for every coloured voxel, block by block in the order blocks got colours.
  template <typename Visit>
  void forEach(Visit&& visit) const {
    for (size_t slot = 0; slot < blocks_.size(); ++slot) {
      const BlockIndex block = unpackIndex(table_.keyOf(static_cast<uint32_t>(slot)));
      const BlockColors& colors = blocks_[slot];
      size_t i = 0;
      for (int w = 0; w < 8; ++w) {
        for (uint64_t bits = colors.has[w]; bits != 0; bits &= bits - 1) {
          visit(voxelOfOffset(block, w * 64 + __builtin_ctzll(bits)), colors.packed[i++]);
        }
      }
    }
  }
  // Removes the colours of the voxels for which remove(ijk) is true, looking only into the blocks
  // for which may_hold(block) is true. Blocks left without colours keep their entry (the table
  // cannot delete) until they are more than half of all: then the store is rebuilt without them,
  // so clearing and cropping over a long mission keep its memory bounded.
  template <typename MayHold, typename Remove>
  void eraseIf(MayHold&& may_hold, Remove&& remove) {
    size_t empty = 0;
    for (size_t slot = 0; slot < blocks_.size(); ++slot) {
      BlockColors& colors = blocks_[slot];
      if (!colors.packed.empty()) {
        const BlockIndex block = unpackIndex(table_.keyOf(static_cast<uint32_t>(slot)));
        if (may_hold(block)) colors.eraseIf(block, remove);
      }
      empty += colors.packed.empty();
    }
    if (empty * 2 <= blocks_.size()) return;
    ColorStore kept;
    forEach([&](const VoxelIndex& ijk, int32_t packed) { kept.set(ijk, packed); });
    *this = std::move(kept);
  }
  // Makes `packed_by_offset` (ascending offsets) the only colours of `block`. Precondition:
  // inPackRange(block).
  template <typename Range>
  void replaceBlock(const BlockIndex& block, const Range& packed_by_offset) {
    uint32_t slot = table_.find(packIndex(block));
    if (slot == BlockTable::kNone) {
      if (packed_by_offset.begin() == packed_by_offset.end()) return;
      bool inserted;
      slot = table_.findOrInsert(packIndex(block), inserted);
      blocks_.emplace_back();
    }
    BlockColors& colors = blocks_[slot];
    colors = BlockColors();
    for (const auto& [offset, packed] : packed_by_offset) {
      colors.has[offset >> 6] |= 1ull << (offset & 63);
      colors.packed.push_back(packed);
    }
    uint16_t before = 0;
    for (int w = 0; w < 8; ++w) {
      colors.before[w] = before;
      before = static_cast<uint16_t>(before + __builtin_popcountll(colors.has[w]));
    }
  }
  // The colours of `block` as (offset, packed), ascending offset.
  std::vector<std::pair<int, int32_t>> blockColors(const BlockIndex& block) const {
    std::vector<std::pair<int, int32_t>> out;
    if (!inPackRange(block)) return out;
    const uint32_t slot = table_.find(packIndex(block));
    if (slot == BlockTable::kNone) return out;
    const BlockColors& colors = blocks_[slot];
    size_t i = 0;
    for (int w = 0; w < 8; ++w) {
      for (uint64_t bits = colors.has[w]; bits != 0; bits &= bits - 1) {
        out.emplace_back(w * 64 + __builtin_ctzll(bits), colors.packed[i++]);
      }
    }
    return out;
  }
  void clear() { *this = ColorStore(); }
  // Blocks with an entry, including those left without colours that eraseIf has not yet dropped.
  size_t numBlocks() const { return blocks_.size(); }
  size_t memoryBytes() const {
    size_t bytes = sizeof(*this) + table_.memoryBytes() + blocks_.capacity() * sizeof(BlockColors);
    for (const BlockColors& colors : blocks_) bytes += colors.packed.capacity() * sizeof(int32_t);
    return bytes;
  }

 private:
  BlockTable table_;  // packed block index -> slot in blocks_
  std::vector<BlockColors> blocks_;
};

}  // namespace cenote::mapping::detail
