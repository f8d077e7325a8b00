// voxel_sets.h: the free and occupied voxels of our map and of an OctoMap tree (pruned leaves
// expanded to voxels of our size), as sorted packed indices, for voxel-by-voxel comparisons in the
// tests and in bench/map_bench.cpp. Threads: pure functions (the map is read through a ConstAccessor).
#pragma once

#include <octomap/OcTree.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "common/point_batch.h"
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

// The batch's points as OctoMap's point cloud (for insertPointCloud from batch.origin).
octomap::Pointcloud toOctomap(const PointBatch& batch);

// OctoMap's OcTree::insertPointCloud of the batch from its origin (lazy_eval off).
void insertPointCloud(octomap::OcTree& tree, const PointBatch& batch, double max_range_m, bool discretize);

// Calls visit(ijk, leaf) for each voxel of the map's size that a leaf of `tree` stands for: a pruned
// leaf of side 2^k voxels stands for (2^k)^3 of them. `leaf` is the tree's leaf iterator.
template <typename Visit>
void forEachLeafVoxel(const octomap::OcTree& tree, const OccupancyMap& map, Visit&& visit) {
  const double s = map.voxelSize();
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    const double size = leaf.getSize();
    const int n = static_cast<int>(std::lround(size / s));
    const octomap::point3d c = leaf.getCoordinate();
    const VoxelIndex first = map.toIndex(
        Eigen::Vector3d(c.x() - size / 2 + s / 2, c.y() - size / 2 + s / 2, c.z() - size / 2 + s / 2));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) visit(VoxelIndex(first + VoxelIndex(i, j, k)), leaf);
  }
}

}  // namespace cenote::mapping::test
