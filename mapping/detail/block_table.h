// block_table.h: an open-addressing hash table from a packed 3D integer index to a dense slot
// number, for the per-batch scratch of integration (no deletion; clear() keeps the capacity).
// Indices must lie within +-2^20 on each axis (checked by the caller).
// Threads: one owner; not synchronised.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace cenote::mapping::detail {

inline uint64_t packIndex(const Eigen::Vector3i& v) {
  constexpr int64_t kBias = 1 << 20;
  return (static_cast<uint64_t>(v.x() + kBias) << 42) | (static_cast<uint64_t>(v.y() + kBias) << 21) |
         static_cast<uint64_t>(v.z() + kBias);
}
// Whether packIndex() can hold v: every coordinate within [-2^20, 2^20).
inline bool inPackRange(const Eigen::Vector3i& v) {
  constexpr uint32_t kBias = 1u << 20;
  return ((static_cast<uint32_t>(v.x()) + kBias) | (static_cast<uint32_t>(v.y()) + kBias) |
          (static_cast<uint32_t>(v.z()) + kBias)) >>
             21 ==
         0;
}
inline Eigen::Vector3i unpackIndex(uint64_t key) {
  constexpr int64_t kBias = 1 << 20;
  constexpr uint64_t kMask = (1u << 21) - 1;
  return Eigen::Vector3i(static_cast<int>(static_cast<int64_t>((key >> 42) & kMask) - kBias),
                         static_cast<int>(static_cast<int64_t>((key >> 21) & kMask) - kBias),
                         static_cast<int>(static_cast<int64_t>(key & kMask) - kBias));
}

class BlockTable {
 public:
  static constexpr uint64_t kEmpty = ~0ull;
  static constexpr uint32_t kNone = ~0u;

  BlockTable() { rehash(1024); }

  // The slot of `key`, inserting it as slot size() when absent (inserted set to true).
  uint32_t findOrInsert(uint64_t key, bool& inserted) {
    if ((size_ + 1) * 2 > keys_.size()) rehash(keys_.size() * 2);
    size_t i = hash(key) & mask_;
    while (true) {
      if (keys_[i] == key) {
        inserted = false;
        return slots_[i];
      }
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        slots_[i] = static_cast<uint32_t>(size_);
        order_.push_back(key);
        inserted = true;
        return static_cast<uint32_t>(size_++);
      }
      i = (i + 1) & mask_;
    }
  }
  uint32_t find(uint64_t key) const {
    size_t i = hash(key) & mask_;
    while (true) {
      if (keys_[i] == key) return slots_[i];
      if (keys_[i] == kEmpty) return kNone;
      i = (i + 1) & mask_;
    }
  }
  size_t size() const { return size_; }
  size_t memoryBytes() const {
    return keys_.capacity() * sizeof(uint64_t) + slots_.capacity() * sizeof(uint32_t) +
           order_.capacity() * sizeof(uint64_t);
  }
  // Key of slot s (slots are numbered in insertion order).
  uint64_t keyOf(uint32_t slot) const { return order_[slot]; }
  void clear() {
    if (size_ == 0) return;
    std::fill(keys_.begin(), keys_.end(), kEmpty);
    order_.clear();
    size_ = 0;
  }

 private:
  static size_t hash(uint64_t key) {
    // MurmurHash3's fmix64: every input bit moves the low bits used as the bucket.
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdull;
    key ^= key >> 33;
    key *= 0xc4ceb9fe1a85ec53ull;
    key ^= key >> 33;
    return static_cast<size_t>(key);
  }
  void rehash(size_t capacity) {
    std::vector<uint64_t> old = std::move(order_);
    keys_.assign(capacity, kEmpty);
    slots_.assign(capacity, kNone);
    mask_ = capacity - 1;
    order_.clear();
    order_.reserve(capacity / 2);
    size_ = 0;
    bool inserted;
    for (uint64_t key : old) findOrInsert(key, inserted);
  }

  std::vector<uint64_t> keys_;
  std::vector<uint32_t> slots_;
  std::vector<uint64_t> order_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

}  // namespace cenote::mapping::detail
