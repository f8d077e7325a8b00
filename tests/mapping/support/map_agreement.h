// map_agreement.h: a map's voxel states against a reference map's (the map built from scratch with
// the true poses), as pose corrections are judged (tests/mapping/history/, bench/correction_bench.cpp):
// the share of the voxels known in either that are in the same state, the reference's occupied
// voxels the map makes free (what a planner would trust and hit) or leaves unknown, and how many of
// the map's occupied voxels lie near a true surface.
// Units: metres. Threads: reads each map through an accessor of its own.
#pragma once

#include <array>
#include <cstdint>

#include "mapping/integration/voxel_ray.h"
#include "mapping/occupancy_map.h"
#include "tests/mapping/support/analytic_scene.h"
#include "tests/mapping/support/known_blocks.h"

namespace cenote::mapping::test {

struct MapAgreement {
  uint64_t known = 0;                  // voxels known in either map
  uint64_t same = 0;                   // ... in the same state in both
  uint64_t reference_occupied = 0;     // occupied in the reference
  uint64_t occupied_made_free = 0;     // occupied in the reference, free in the map
  uint64_t occupied_made_unknown = 0;  // occupied in the reference, unknown in the map
  double agreement() const { return known == 0 ? 1.0 : double(same) / known; }
  double madeFree() const { return reference_occupied == 0 ? 0.0 : double(occupied_made_free) / reference_occupied; }
};

inline MapAgreement compareStates(const OccupancyMap& map, const OccupancyMap& reference) {
  auto acc = map.constAccessor();
  auto ref = reference.constAccessor();
  MapAgreement a;
  for (const BlockIndex& block : blocksKnownInEither(acc, ref)) {
    std::array<uint64_t, 8> km, om, kr, orf;
    acc.readBlockMasks(block, km, om);
    ref.readBlockMasks(block, kr, orf);
    for (int w = 0; w < 8; ++w) {
      const uint64_t either = km[w] | kr[w];
      a.known += __builtin_popcountll(either);
      a.same += __builtin_popcountll(either & ~(km[w] ^ kr[w]) & ~(om[w] ^ orf[w]));
      a.reference_occupied += __builtin_popcountll(orf[w]);
      a.occupied_made_free += __builtin_popcountll(orf[w] & km[w] & ~om[w]);
      a.occupied_made_unknown += __builtin_popcountll(orf[w] & ~km[w]);
    }
  }
  return a;
}

// The share of the map's occupied voxels whose centre lies within max_distance_m of a surface of
// `scene` (1 for a map with none).
inline double occupiedNearSurfaces(const OccupancyMap& map, const Scene& scene, double max_distance_m) {
  auto acc = map.constAccessor();
  const double s = map.config().voxel_size_m;
  uint64_t occupied = 0, near = 0;
  for (const BlockIndex& block : acc.knownBlocks()) {
    std::array<uint64_t, 8> known, occ;
    acc.readBlockMasks(block, known, occ);
    for (int w = 0; w < 8; ++w) {
      for (uint64_t bits = occ[w]; bits != 0; bits &= bits - 1) {
        const VoxelIndex ijk = voxelOfOffset(block, w * 64 + __builtin_ctzll(bits));
        ++occupied;
        near += scene.distanceToSurface(voxelCentre(ijk, s)) <= max_distance_m;
      }
    }
  }
  return occupied == 0 ? 1.0 : double(near) / occupied;
}

}  // namespace cenote::mapping::test
