// leaf_index.h: a flat open-addressing hash from block index to the values and known mask of the
// log-odds tree's leaf there (Bonxai-style), beside the OpenVDB tree, for lookups.
// Why: a random lookup through an OpenVDB accessor walks root -> internal -> internal -> leaf ->
// buffer, one dependent cache miss after another; here it probes one slot of a table that stays in
// cache (32 bytes per slot, at most half full) and then reads the mask word and the value, two
// independent loads. A batch of lookups can prefetch both for a group of voxels ahead.
// Indices: voxel_types.h. Blocks must lie within +-2^20 on each axis to be inserted (the map's
// voxels, within +-kMaxVoxelIndex, always do); find() reports blocks beyond absent.
// Threads: none; OccupancyMap guards it with its grid mutex, like the tree. Entries point into the
// tree's leaves: insert (or erase) with every leaf the tree gains (or loses), or rebuild.
#pragma once

#include <cstdint>
#include <vector>

#include "mapping/detail/block_table.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping::detail {

// Where one leaf keeps its voxels: values[offsetInBlock(ijk)], known bit offsetInBlock(ijk).
struct LeafRef {
  const float* values = nullptr;
  const uint64_t* known = nullptr;

  bool logOdds(int offset, float& l) const {
    if (((known[offset >> 6] >> (offset & 63)) & 1) == 0) return false;
    l = values[offset];
    return true;
  }
  void prefetch(int offset) const {
    __builtin_prefetch(known + (offset >> 6));
    __builtin_prefetch(values + offset);
  }
};

class LeafIndex {
 public:
  LeafIndex() { rehash(kMinCapacity); }

  // The leaf of a block; nullptr when the tree has none there.
  const LeafRef* find(const BlockIndex& b) const { return inPackRange(b) ? find(packIndex(b)) : nullptr; }
  // The same by packIndex(b).
  const LeafRef* find(uint64_t key) const {
    for (size_t i = bucket(key);; i = (i + 1) & mask_) {
      const Slot& slot = slots_[i];
      if (slot.key == key) return &slot.ref;
      if (slot.key == kEmpty) return nullptr;
    }
  }
  // Brings the block's first table slot into cache.
  void prefetch(const BlockIndex& b) const {
    if (inPackRange(b)) __builtin_prefetch(&slots_[bucket(packIndex(b))]);
  }

  // Adds or replaces a block's leaf. Precondition: inPackRange(b).
  void insert(const BlockIndex& b, const LeafRef& ref) {
    const uint64_t key = packIndex(b);
    for (size_t i = bucket(key);; i = (i + 1) & mask_) {
      Slot& slot = slots_[i];
      if (slot.key == key) {
        slot.ref = ref;
        return;
      }
      if (slot.key == kEmpty) break;
    }
    if ((size_ + 1) * 2 > slots_.size()) rehash(slots_.size() * 2);
    place(Slot{key, ref});
    ++size_;
  }
  // Removes a block's entry (none: nothing happens). Backward-shift deletion: the entries after it
  // in its probe run move up where their own probe path allows, so find() needs no tombstones.
  void erase(const BlockIndex& b) {
    if (!inPackRange(b)) return;
    const uint64_t key = packIndex(b);
    size_t hole = bucket(key);
    while (slots_[hole].key != key) {
      if (slots_[hole].key == kEmpty) return;
      hole = (hole + 1) & mask_;
    }
    for (size_t i = (hole + 1) & mask_; slots_[i].key != kEmpty; i = (i + 1) & mask_) {
      // The entry at i may fill the hole when the hole lies on its probe path: home .. i.
      if (((i - bucket(slots_[i].key)) & mask_) >= ((i - hole) & mask_)) {
        slots_[hole] = slots_[i];
        hole = i;
      }
    }
    slots_[hole] = Slot{};
    --size_;
  }
  void clear() {
    slots_.clear();
    size_ = 0;
    rehash(kMinCapacity);
  }
  // Shrinks the table to the smallest capacity that holds its entries (at most half full) once
  // erasing has left it more than 8 times too large: after a crop or reset the map's memory falls
  // with its blocks (a table grown to 1M slots is 32 MB). Same entries; the order of slots changes.
  void shrinkToFit() {
    size_t capacity = kMinCapacity;
    while (capacity < 2 * size_) capacity *= 2;
    if (capacity * 8 <= slots_.size()) rehash(capacity);
  }
  size_t size() const { return size_; }
  size_t memoryBytes() const { return sizeof(*this) + slots_.capacity() * sizeof(Slot); }

 private:
  static constexpr uint64_t kEmpty = ~0ull;
  static constexpr size_t kMinCapacity = 64;
  struct alignas(32) Slot {
    uint64_t key = kEmpty;
    LeafRef ref;
  };

  // Fibonacci hashing: the top bits of key * 2^64 / phi; every bit of the packed x, y, z moves them.
  size_t bucket(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }
  void place(const Slot& slot) {
    size_t i = bucket(slot.key);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask_;
    slots_[i] = slot;
  }
  void rehash(size_t capacity) {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(capacity, Slot{});
    mask_ = capacity - 1;
    shift_ = 64 - __builtin_ctzll(capacity);
    for (const Slot& slot : old) {
      if (slot.key != kEmpty) place(slot);
    }
  }

  std::vector<Slot> slots_;
  size_t mask_ = 0;
  int shift_ = 64;
  size_t size_ = 0;
};

}  // namespace cenote::mapping::detail
