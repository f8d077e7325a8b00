// voxel_sets.h: the free and occupied voxels of our map and of an OctoMap tree (pruned leaves
// expanded to voxels of our size), as sorted packed indices, for voxel-by-voxel comparisons in the
// tests and in bench/map_bench.cpp. Threads: pure functions (the map is read through a ConstAccessor).
#pragma once

#include <octomap/OcTree.h>

#include <cstdint>
#include <vector>

#include "mapping/occupancy_map.h"

namespace cenote::mapping::test {

struct VoxelSets {
  std::vector<uint64_t> free, occupied;  // sorted packed voxel indices
};

VoxelSets voxelSets(const OccupancyMap& map);
// `map` gives the voxel size and the world-to-index conversion.
VoxelSets voxelSets(const octomap::OcTree& tree, const OccupancyMap& map);
// How many keys of sorted `a` are not in sorted `b`.
size_t countNotIn(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b);

}  // namespace cenote::mapping::test
