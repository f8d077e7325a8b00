// map_impl.h: the OpenVDB grid behind OccupancyMap, with its colours. Included only by the few .cpp
// files that need the grid (occupancy_map.cpp, io/*.cpp): every file that sees openvdb/ pays a
// minute of compile time on 2 cores.
// Threads: see occupancy_map.h; grid_mutex guards the grid and colours, writer_mutex serialises writers.
#pragma once

#include <openvdb/openvdb.h>

#include <atomic>
#include <mutex>
#include <shared_mutex>

#include "mapping/detail/color_store.h"
#include "mapping/detail/leaf_index.h"
#include "mapping/integration/projective_batch.h"
#include "mapping/integration/ray_batch.h"
#include "mapping/occupancy_map.h"

namespace cenote::mapping::detail {

// Colour of a voxel packed into an int32: bits 0-23 RGB (R lowest), bits 24-30 the number of
// batches averaged (saturating at 127: the mean then moves as an exponential average).
inline int32_t packColor(const std::array<uint8_t, 3>& rgb, int count) {
  return static_cast<int32_t>(rgb[0] | (rgb[1] << 8) | (rgb[2] << 16) | (count << 24));
}
inline std::array<uint8_t, 3> unpackColor(int32_t packed) {
  return {static_cast<uint8_t>(packed & 255), static_cast<uint8_t>((packed >> 8) & 255),
          static_cast<uint8_t>((packed >> 16) & 255)};
}
inline int colorCount(int32_t packed) { return (packed >> 24) & 127; }

// The log-odds tree: OpenVDB's FloatTree has internal nodes of 32^3 and 16^3 children (264 KB and
// 33 KB each, however few leaves they hold: 2.2 MB of the bench's 7.4 MB grid at 5 cm); this one
// has 16^3 and 8^3 (33 KB and 4 KB), over the same 8^3-voxel leaves (LeafNode<float, 3>, shared
// with FloatTree, so .vdb files still hold a standard FloatGrid: map_io.cpp copies the leaves).
using LogOddsTree = openvdb::tree::Tree4<float, 4, 3, 3>::Type;
using LogOddsGrid = openvdb::Grid<LogOddsTree>;

struct MapImpl {
  LogOddsGrid::Ptr log_odds;  // active voxel = known; value = log-odds
  ColorStore color;           // where some point hit
  LeafIndex leaf_index;       // block -> leaf of log_odds, for lookups; kept in step with the tree
  mutable detail::FairSharedMutex grid_mutex;
  std::mutex writer_mutex;
  std::atomic<uint64_t> version{0};
  RayBatch scratch;
  ProjectiveBatch projective_scratch;

  // Adds (or refreshes) a leaf of log_odds in leaf_index. Precondition: inPackRange(block).
  void indexLeaf(LogOddsTree::LeafNodeType& leaf) {
    const openvdb::Coord o = leaf.origin();
    leaf_index.insert(BlockIndex(o.x() >> kBlockShift, o.y() >> kBlockShift, o.z() >> kBlockShift),
                      LeafRef{leaf.buffer().data(), &leaf.getValueMask().template getWord<uint64_t>(0)});
  }
  // Rebuilds leaf_index after leaves were deleted, or the tree was filled another way.
  void reindexLeaves() {
    leaf_index.clear();
    for (auto leaf = log_odds->tree().beginLeaf(); leaf; ++leaf) indexLeaf(*leaf);
  }

  // Frees the trees' nodes serially: Tree's destructor frees them with a TBB parallel_for, whose
  // (uninstrumented) worker threads ThreadSanitizer reports as racing with ours.
  ~MapImpl() {
    if (log_odds) log_odds->tree().root().clear();
  }
};

class MapAccess {
 public:
  static MapImpl& of(OccupancyMap& map) { return *map.impl_; }
  static const MapImpl& of(const OccupancyMap& map) { return *map.impl_; }
};

// OpenVDB index space: our voxel i has its centre at (i + 0.5) * s, so the grids' transform is a
// scale by s and a translation by s / 2.
openvdb::math::Transform::Ptr makeTransform(double voxel_size_m);

}  // namespace cenote::mapping::detail
