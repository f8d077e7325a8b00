// block_snapshot.h: every known block of a map copied out, for the tests of readers during a pose
// correction (each block a reader sees must equal its snapshot before or after the correction).
// Threads: reads the map through one accessor of its own.
#pragma once

#include <array>
#include <map>

#include "mapping/occupancy_map.h"

namespace cenote::mapping::test {

using BlockSnapshot = std::map<std::array<int, 3>, BlockView>;

inline BlockSnapshot snapshotBlocks(const OccupancyMap& map) {
  BlockSnapshot out;
  auto acc = map.constAccessor();
  for (const BlockIndex& b : acc.knownBlocks()) acc.readBlock(b, out[{b.x(), b.y(), b.z()}]);
  return out;
}

// The same known voxels with the same log-odds (values where unknown are ignored).
inline bool sameBlock(const BlockView& a, const BlockView& b) {
  if (a.known != b.known) return false;
  for (int i = 0; i < kBlockVoxels; ++i) {
    if (((a.known[i >> 6] >> (i & 63)) & 1) && a.log_odds[i] != b.log_odds[i]) return false;
  }
  return true;
}

// Block b of the snapshot; all unknown when the map did not know it.
inline const BlockView& blockIn(const BlockSnapshot& snapshot, const BlockIndex& b) {
  static const BlockView kUnknown{};
  const auto it = snapshot.find({b.x(), b.y(), b.z()});
  return it == snapshot.end() ? kUnknown : it->second;
}

}  // namespace cenote::mapping::test
