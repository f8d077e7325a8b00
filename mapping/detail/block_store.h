// block_store.h: the voxels of OccupancyMap: a flat open-addressing hash from block index to a
// block of 8x8x8 log-odds (Bonxai-style), with the colours of hit voxels stored sparsely per block.
// Chosen over an OpenVDB tree (which the map used before) for memory and lookups: OpenVDB's
// internal nodes cost 32 KB and 264 KB each however few leaves they hold (a quarter of the map's
// memory at 5 cm), and a lookup walks root -> two internal nodes -> leaf; here it is one probe
// of a table that stays in cache (16 bytes per slot, at most half full) and one read in the block.
// Colours: only hit voxels have one (a few per cent of the known voxels), so a block keeps a
// 512-bit mask and the packed colours of its set bits in offset order, not 512 of them.
// Unknown voxels hold NaN in log_odds, and their bit in `known` is clear; the two are kept in
// step, so a lookup reads one float (NaN: unknown) without touching the mask.
// .vdb files still hold OpenVDB grids (mapping/io/map_io.cpp converts both ways).
// Units: log-odds (log_odds.h); indices as voxel_types.h. Blocks must lie within +-2^20 on each
// axis (voxels within +-2^23: what OccupancyMap accepts); find() reports blocks outside absent.
// Threads: none; OccupancyMap guards the store with its grid mutex. A block's address stays valid
// until the block is erased (the table rehashes pointers, the blocks never move).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "mapping/detail/block_table.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping::detail {

// Colours of the hit voxels of one block: bit offsetInBlock(ijk) of `has`, and the packed colours
// (map_impl.h, packColor) of the set bits in ascending offset order.
struct BlockColors {
  std::array<uint64_t, 8> has{};
  std::vector<int32_t> packed;

  // Index in `packed` of the voxel at `offset` (whether or not it has a colour).
  size_t rank(int offset) const {
    const int w = offset >> 6;
    size_t r = 0;
    for (int i = 0; i < w; ++i) r += static_cast<size_t>(__builtin_popcountll(has[i]));
    return r + static_cast<size_t>(__builtin_popcountll(has[w] & ((1ull << (offset & 63)) - 1)));
  }
  bool get(int offset, int32_t& value) const {
    if (((has[offset >> 6] >> (offset & 63)) & 1) == 0) return false;
    value = packed[rank(offset)];
    return true;
  }
  void set(int offset, int32_t value) {
    const size_t r = rank(offset);
    uint64_t& word = has[offset >> 6];
    const uint64_t bit = 1ull << (offset & 63);
    if (word & bit) {
      packed[r] = value;
      return;
    }
    word |= bit;
    packed.insert(packed.begin() + static_cast<std::ptrdiff_t>(r), value);
  }
  bool empty() const { return packed.empty(); }
};

struct alignas(64) VoxelBlock {
  std::array<float, kBlockVoxels> log_odds;  // NaN where unknown
  std::array<uint64_t, 8> known{};           // bit offsetInBlock(ijk): observed
  std::unique_ptr<BlockColors> colors;       // null while no voxel of the block has a colour
  BlockIndex index = BlockIndex::Zero();

  explicit VoxelBlock(const BlockIndex& block) : index(block) {
    log_odds.fill(std::numeric_limits<float>::quiet_NaN());
  }
  bool hasKnown() const {
    uint64_t any = 0;
    for (uint64_t w : known) any |= w;
    return any != 0;
  }
};

class BlockStore {
 public:
  BlockStore() { rehash(kMinCapacity); }

  static bool inRange(const BlockIndex& b) {
    constexpr uint32_t kBias = 1u << 20;
    return ((static_cast<uint32_t>(b.x()) + kBias) | (static_cast<uint32_t>(b.y()) + kBias) |
            (static_cast<uint32_t>(b.z()) + kBias)) >> 21 == 0;
  }

  // The block, or nullptr when absent (always for blocks outside +-2^20).
  const VoxelBlock* find(const BlockIndex& b) const {
    if (!inRange(b)) return nullptr;
    const uint64_t key = packIndex(b);
    for (size_t i = bucket(key);; i = (i + 1) & mask_) {
      const Slot& slot = slots_[i];
      if (slot.key == key) return slot.block;
      if (slot.key == kEmpty) return nullptr;
    }
  }
  VoxelBlock* find(const BlockIndex& b) {
    return const_cast<VoxelBlock*>(static_cast<const BlockStore&>(*this).find(b));
  }
  // Brings the table slot of the block into cache (a batch of lookups issues these ahead).
  void prefetch(const BlockIndex& b) const { __builtin_prefetch(&slots_[bucket(packIndex(b))]); }

  // The block, created all unknown when absent. Precondition: inRange(b).
  VoxelBlock& touch(const BlockIndex& b) {
    const uint64_t key = packIndex(b);
    for (size_t i = bucket(key);; i = (i + 1) & mask_) {
      Slot& slot = slots_[i];
      if (slot.key == key) return *slot.block;
      if (slot.key == kEmpty) break;
    }
    blocks_.push_back(std::make_unique<VoxelBlock>(b));
    VoxelBlock& block = *blocks_.back();
    if (blocks_.size() * 2 > slots_.size()) {
      rehash(slots_.size() * 2);
    } else {
      insert(key, &block);
    }
    return block;
  }

  // Every block, in creation order (blocks may hold no known voxel; see VoxelBlock::hasKnown).
  const std::vector<std::unique_ptr<VoxelBlock>>& blocks() const { return blocks_; }

  // Erases the blocks for which keep(block) is false.
  template <typename Keep>
  void eraseUnless(Keep&& keep) {
    size_t kept = 0;
    for (auto& block : blocks_) {
      if (keep(*block)) blocks_[kept++] = std::move(block);
    }
    blocks_.resize(kept);
    rehash(slots_.size());
  }
  void clear() {
    blocks_.clear();
    rehash(kMinCapacity);
  }

  size_t memoryBytes() const {
    size_t bytes = sizeof(*this) + slots_.capacity() * sizeof(Slot) + blocks_.capacity() * sizeof(blocks_[0]);
    for (const auto& block : blocks_) {
      bytes += sizeof(VoxelBlock);
      if (block->colors) bytes += sizeof(BlockColors) + block->colors->packed.capacity() * sizeof(int32_t);
    }
    return bytes;
  }

 private:
  static constexpr uint64_t kEmpty = ~0ull;
  static constexpr size_t kMinCapacity = 64;
  struct Slot {
    uint64_t key = kEmpty;
    VoxelBlock* block = nullptr;
  };

  // Fibonacci hashing: the top bits of key * 2^64 / phi; every bit of the packed x, y, z moves them.
  size_t bucket(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }
  void insert(uint64_t key, VoxelBlock* block) {
    size_t i = bucket(key);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask_;
    slots_[i] = Slot{key, block};
  }
  void rehash(size_t capacity) {
    while (blocks_.size() * 2 > capacity) capacity *= 2;
    slots_.assign(capacity, Slot{});
    mask_ = capacity - 1;
    shift_ = 64 - __builtin_ctzll(capacity);
    for (const auto& block : blocks_) insert(packIndex(block->index), block.get());
  }

  std::vector<Slot> slots_;
  std::vector<std::unique_ptr<VoxelBlock>> blocks_;
  size_t mask_ = 0;
  int shift_ = 64;
};

}  // namespace cenote::mapping::detail
