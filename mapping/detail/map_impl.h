// map_impl.h: the state behind OccupancyMap (its voxels in a BlockStore, locks, scratch).
// Included only by occupancy_map.cpp and io/map_io.cpp (which converts to and from OpenVDB grids).
// Threads: see occupancy_map.h; grid_mutex guards the store, writer_mutex serialises writers.
#pragma once

#include <array>
#include <atomic>
#include <mutex>
#include <shared_mutex>

#include "mapping/detail/block_store.h"
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

struct MapImpl {
  BlockStore store;  // log-odds (known voxels) and colours (voxels some point hit)
  mutable detail::FairSharedMutex grid_mutex;
  std::mutex writer_mutex;
  std::atomic<uint64_t> version{0};
  RayBatch scratch;
  ProjectiveBatch projective_scratch;
};

class MapAccess {
 public:
  static MapImpl& of(OccupancyMap& map) { return *map.impl_; }
  static const MapImpl& of(const OccupancyMap& map) { return *map.impl_; }
};

}  // namespace cenote::mapping::detail
