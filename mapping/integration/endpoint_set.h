// endpoint_set.h: the distinct endpoint voxels of a batch of points (ray ends, or back-projected
// pixels), each with the colour sums of its points, in order of first appearance. Integration
// deduplicates endpoints with it (RayBatch, ProjectiveBatch) and takes each hit voxel's mean colour
// from it. Units: voxel indices, colours 0..255. Threads: one owner.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "mapping/detail/block_table.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping {

// The mean colour of the points that hit a voxel.
struct EndpointColor {
  VoxelIndex ijk;
  std::array<uint8_t, 3> rgb;
};

class EndpointSet {
 public:
  EndpointSet() { clear(); }

  void clear() {
    table_.clear();
    voxels_.clear();
    sums_.clear();
    recent_.fill({detail::BlockTable::kEmpty, 0});
    last_ = kNoVoxel;
  }

  // Adds one point's voxel; rgb: its colour, or null for an uncoloured point. Neighbouring pixels
  // mostly fall into the same voxel (6 pixels per 5 cm voxel at 5 m): the last voxel's slot is
  // kept, which skips most lookups. The next row of pixels mostly falls into the voxels of the
  // row before: a small direct-mapped cache of recent voxels (4 KiB, in L1) answers most of the
  // rest, before the table (hundreds of KiB, a cache miss and a longer hash per probe).
  void add(const VoxelIndex& ijk, const uint8_t* rgb) {
    if (ijk != last_) {
      last_ = ijk;
      const uint64_t key = detail::packIndex(ijk);
      Recent& recent = recent_[(key * 0x9e3779b97f4a7c15ull) >> (64 - kRecentBits)];  // Fibonacci hashing
      if (recent.key != key) {
        bool inserted;
        recent = {key, table_.findOrInsert(key, inserted)};
        if (inserted) {
          voxels_.push_back(ijk);
          sums_.push_back({0, 0, 0, 0});
        }
      }
      last_slot_ = recent.slot;
    }
    if (rgb != nullptr) {
      auto& sum = sums_[last_slot_];
      for (int k = 0; k < 3; ++k) sum[k] += rgb[k];
      sum[3] += 1;
    }
  }

  // Adds every voxel of `other`, in its order, with its colour sums.
  void merge(const EndpointSet& other) {
    for (size_t e = 0; e < other.voxels_.size(); ++e) {
      bool inserted;
      const uint32_t slot = table_.findOrInsert(detail::packIndex(other.voxels_[e]), inserted);
      if (inserted) {
        voxels_.push_back(other.voxels_[e]);
        sums_.push_back({0, 0, 0, 0});
      }
      for (int k = 0; k < 4; ++k) sums_[slot][k] += other.sums_[e][k];
    }
    last_ = kNoVoxel;
  }

  const std::vector<VoxelIndex>& voxels() const { return voxels_; }
  // Mean colour of voxels()[i], rounded to nearest; only for a voxel with coloured points.
  EndpointColor meanColor(size_t i) const {
    const auto& sum = sums_[i];
    const uint32_t c = sum[3];
    return {voxels_[i],
            {static_cast<uint8_t>((sum[0] + c / 2) / c), static_cast<uint8_t>((sum[1] + c / 2) / c),
             static_cast<uint8_t>((sum[2] + c / 2) / c)}};
  }

 private:
  struct Recent {
    uint64_t key;  // packIndex of a voxel, or BlockTable::kEmpty (no voxel packs to it)
    uint32_t slot;
  };
  static constexpr int kRecentBits = 8;
  std::array<Recent, size_t{1} << kRecentBits> recent_;  // voxels' slots, by hash of their key (emptied by clear())
  detail::BlockTable table_;                             // voxel -> index in voxels_
  std::vector<VoxelIndex> voxels_;
  std::vector<std::array<uint32_t, 4>> sums_;                                      // r, g, b, count per voxel
  static inline const VoxelIndex kNoVoxel{std::numeric_limits<int>::min(), 0, 0};  // beyond any map
  VoxelIndex last_ = kNoVoxel;  // the voxel of the last add(), so a run of equal voxels skips the table
  uint32_t last_slot_ = 0;
};

}  // namespace cenote::mapping
