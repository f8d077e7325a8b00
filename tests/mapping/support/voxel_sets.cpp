#include "tests/mapping/support/voxel_sets.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>

namespace cenote::mapping::test {

namespace {

uint64_t packVoxel(const VoxelIndex& ijk) {
  constexpr int64_t kBias = int64_t{1} << 20;  // beyond kMaxVoxelIndex: every voxel packs to its own key
  return static_cast<uint64_t>(ijk.x() + kBias) << 42 | static_cast<uint64_t>(ijk.y() + kBias) << 21 |
         static_cast<uint64_t>(ijk.z() + kBias);
}

}  // namespace

VoxelSets voxelSets(const OccupancyMap& map) {
  VoxelSets sets;
  const auto acc = map.constAccessor();
  for (const BlockIndex& block : acc.knownBlocks()) {
    std::array<uint64_t, 8> known, occupied;
    acc.readBlockMasks(block, known, occupied);
    for (int o = 0; o < kBlockVoxels; ++o) {
      if (!((known[o >> 6] >> (o & 63)) & 1)) continue;
      const bool is_occupied = (occupied[o >> 6] >> (o & 63)) & 1;
      (is_occupied ? sets.occupied : sets.free).push_back(packVoxel(voxelOfOffset(block, o)));
    }
  }
  std::sort(sets.free.begin(), sets.free.end());
  std::sort(sets.occupied.begin(), sets.occupied.end());
  return sets;
}

// OctoMap's leaves, pruned ones expanded to their voxels.
VoxelSets voxelSets(const octomap::OcTree& tree, const OccupancyMap& map) {
  VoxelSets sets;
  forEachLeafVoxel(tree, map, [&](const VoxelIndex& ijk, const auto& leaf) {
    (tree.isNodeOccupied(*leaf) ? sets.occupied : sets.free).push_back(packVoxel(ijk));
  });
  std::sort(sets.free.begin(), sets.free.end());
  std::sort(sets.occupied.begin(), sets.occupied.end());
  return sets;
}

size_t countNotIn(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
  std::vector<uint64_t> rest;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(rest));
  return rest.size();
}

octomap::Pointcloud toOctomap(const PointBatch& batch) {
  octomap::Pointcloud cloud;
  cloud.reserve(batch.size());
  for (const auto& p : batch.points) cloud.push_back(p.x(), p.y(), p.z());
  return cloud;
}

void insertPointCloud(octomap::OcTree& tree, const PointBatch& batch, double max_range_m, bool discretize) {
  tree.insertPointCloud(toOctomap(batch), octomap::point3d(batch.origin.x(), batch.origin.y(), batch.origin.z()),
                        max_range_m, false, discretize);
}

}  // namespace cenote::mapping::test
