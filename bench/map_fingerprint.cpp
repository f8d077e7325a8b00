#include "bench/map_fingerprint.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "mapping/integration/voxel_ray.h"

namespace cenote::bench {
namespace {

void mixDouble(uint64_t& h, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  fnvMixBytes(h, bits);
}

}  // namespace

uint64_t mapFingerprint(const mapping::OccupancyMap& map) {
  const auto acc = map.constAccessor();
  uint64_t h = kFnvOffset;
  mapping::BlockView view;
  for (const mapping::BlockIndex& b : acc.knownBlocks()) {
    acc.readBlock(b, view);
    for (int i = 0; i < 3; ++i) fnvMixBytes(h, static_cast<uint64_t>(static_cast<int64_t>(b[i])));
    for (int w = 0; w < 8; ++w) {
      fnvMixBytes(h, view.known[w]);
      for (uint64_t rest = view.known[w]; rest != 0; rest &= rest - 1) {
        uint32_t bits;
        std::memcpy(&bits, &view.log_odds[w * 64 + __builtin_ctzll(rest)], 4);
        fnvMixBytes(h, bits);
      }
    }
    for (const mapping::VoxelColor& c : acc.blockColors(b)) {
      fnvMixBytes(h, static_cast<uint64_t>(c.offset) | uint64_t{c.rgb[0]} << 16 | uint64_t{c.rgb[1]} << 24 |
                         uint64_t{c.rgb[2]} << 32 | uint64_t{c.count} << 40);
    }
  }
  return h;
}

uint64_t distanceFingerprint(const mapping::OccupancyMap& map, const mapping::DistanceField& field) {
  using mapping::BlockIndex;
  std::vector<BlockIndex> blocks;
  for (const BlockIndex& b : map.constAccessor().knownBlocks())
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) blocks.push_back(b + BlockIndex(x, y, z));
  auto less = [](const BlockIndex& a, const BlockIndex& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(blocks.begin(), blocks.end(), less);
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  uint64_t h = kFnvOffset;
  std::vector<Eigen::Vector3d> points(mapping::kBlockVoxels);
  for (const BlockIndex& b : blocks) {
    for (int o = 0; o < mapping::kBlockVoxels; ++o) {
      points[o] = mapping::voxelCentre(mapping::voxelOfOffset(b, o), map.voxelSize());
    }
    for (const mapping::DistanceQuery& q : field.query(points)) {
      mixDouble(h, q.distance_m);
      for (int i = 0; i < 3; ++i) mixDouble(h, q.gradient[i]);
    }
  }
  return h;
}

}  // namespace cenote::bench
