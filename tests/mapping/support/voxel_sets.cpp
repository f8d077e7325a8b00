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

// OctoMap's leaves, pruned ones expanded to their voxels (voxel size `s`).
VoxelSets voxelSets(const octomap::OcTree& tree, const OccupancyMap& map) {
  VoxelSets sets;
  const double s = map.voxelSize();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / s));
    const octomap::point3d c = it.getCoordinate();
    const VoxelIndex first = map.toIndex(
        Eigen::Vector3d(c.x() - size / 2 + s / 2, c.y() - size / 2 + s / 2, c.z() - size / 2 + s / 2));
    std::vector<uint64_t>& out = tree.isNodeOccupied(*it) ? sets.occupied : sets.free;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) out.push_back(packVoxel(first + VoxelIndex(i, j, k)));
  }
  std::sort(sets.free.begin(), sets.free.end());
  std::sort(sets.occupied.begin(), sets.occupied.end());
  return sets;
}

size_t countNotIn(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
  std::vector<uint64_t> rest;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(rest));
  return rest.size();
}

}  // namespace cenote::mapping::test
