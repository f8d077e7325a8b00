// known_blocks.h: the blocks known in either of two maps, which a block-by-block comparison of the
// two maps visits (the mapping tests, bench/correction_bench.cpp). Threads: reads each map only
// through the accessor it is given.
#pragma once

#include <algorithm>
#include <vector>

#include "mapping/occupancy_map.h"

namespace cenote::mapping::test {

// The blocks known in a, in b or in both, each once, sorted by x, then y, then z.
inline std::vector<BlockIndex> blocksKnownInEither(const OccupancyMap::ConstAccessor& a,
                                                   const OccupancyMap::ConstAccessor& b) {
  std::vector<BlockIndex> blocks = a.knownBlocks();
  for (const BlockIndex& block : b.knownBlocks()) blocks.push_back(block);
  std::sort(blocks.begin(), blocks.end(), [](const BlockIndex& x, const BlockIndex& y) {
    return std::lexicographical_compare(x.data(), x.data() + 3, y.data(), y.data() + 3);
  });
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  return blocks;
}

}  // namespace cenote::mapping::test
