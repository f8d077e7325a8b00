// The plain value types of voxel_types.h: merging change records (voxel state names: occupancy_map.cpp).
#include <algorithm>

#include "mapping/voxel_types.h"

namespace cenote::mapping {

void MapDelta::merge(const MapDelta& other) {
  // Both lists are sorted and unique: a linear merge (the server merges every frame's delta into
  // the pending one, which can hold the whole map's blocks while nobody asks for distances).
  const auto middle = static_cast<std::ptrdiff_t>(changed_blocks.size());
  changed_blocks.insert(changed_blocks.end(), other.changed_blocks.begin(), other.changed_blocks.end());
  changed_voxels.extend(other.changed_voxels);
  changed_m.extend(other.changed_m);
  voxels_updated += other.voxels_updated;
  points_used += other.points_used;
  auto less = [](const BlockIndex& a, const BlockIndex& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::inplace_merge(changed_blocks.begin(), changed_blocks.begin() + middle, changed_blocks.end(), less);
  changed_blocks.erase(std::unique(changed_blocks.begin(), changed_blocks.end()), changed_blocks.end());
}

}  // namespace cenote::mapping
