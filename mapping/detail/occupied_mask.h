// occupied_mask.h: the occupied voxels among 64 (one 64-bit word of a leaf's masks: x fixed,
// y * 8 + z) as a bit mask: LogOddsModel::isOccupied (l >= occupied) on the known ones, four
// voxels per SSE2 compare. Why: the frontier update reads every changed block's neighbours
// (readBlockMasks); 27 % of its instructions were this test done voxel by voxel.
// Unknown voxels are never occupied, whatever their stale value. NaN is never occupied (an
// ordered compare, as the scalar >=); -0 >= +0.
// Units: log-odds (log_odds.h). Threads: a pure function of its arguments and the 64 values.
#pragma once

#include <cstdint>

#include "mapping/detail/simd_target.h"

namespace cenote::mapping::detail {

// The portable kernel (ARM, CENOTE_FORCE_SCALAR); tests compare occupiedMask against it.
inline uint64_t occupiedMaskScalar(const float* values, uint64_t known, float occupied) {
  uint64_t occ = 0;
  for (int i = 0; i < 64; ++i) occ |= static_cast<uint64_t>(values[i] >= occupied) << i;
  return occ & known;
}

// Bit i set where known bit i is set and values[i] >= occupied.
inline uint64_t occupiedMask(const float* values, uint64_t known, float occupied) {
#if CENOTE_MAPPING_SSE2
  const __m128 limit = _mm_set1_ps(occupied);
  uint64_t occ = 0;
  for (int g = 0; g < 16; ++g) {
    const __m128 l = _mm_loadu_ps(values + 4 * g);
    occ |= static_cast<uint64_t>(_mm_movemask_ps(_mm_cmpge_ps(l, limit))) << (4 * g);
  }
  return occ & known;
#else
  return occupiedMaskScalar(values, known, occupied);
#endif
}

}  // namespace cenote::mapping::detail
