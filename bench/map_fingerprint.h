// map_fingerprint.h: FNV-1a fingerprints that map_bench prints to compare versions of the map code:
// a faster integration, distance field or clear must print the same hex digits as the one before.
// Threads: pure functions of their arguments (each takes its own ConstAccessor).
#pragma once

#include <cstdint>

#include "mapping/distance/distance_field.h"
#include "mapping/occupancy_map.h"

namespace cenote::bench {

constexpr uint64_t kFnvOffset = 14695981039346656037ull, kFnvPrime = 1099511628211ull;
// Mixes the 8 bytes of `word` into `h`, lowest first.
inline void fnvMixBytes(uint64_t& h, uint64_t word) {
  for (int i = 0; i < 8; ++i) h = (h ^ ((word >> (8 * i)) & 0xFF)) * kFnvPrime;
}

// The whole map: every known block's index, known bits, the exact bits of its known voxels'
// log-odds and its colours (offset, RGB, count), blocks in knownBlocks() order.
uint64_t mapFingerprint(const mapping::OccupancyMap& map);

// The exact bits of the distance field's answers (distance and gradient, which names the nearest
// obstacle) at every voxel centre of the map's known blocks and their 26 neighbour blocks.
uint64_t distanceFingerprint(const mapping::OccupancyMap& map, const mapping::DistanceField& field);

}  // namespace cenote::bench
