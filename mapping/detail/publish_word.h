// publish_word.h: one batch's log-odds updates applied to 64 voxels of a leaf at once (one 64-bit
// word of its masks: x fixed, y * 8 + z), eight voxels per AVX2 instruction where the CPU has it,
// else four per SSE2 instruction (simd_target.h; elsewhere, e.g. ARM, publishWordScalar, voxel by
// voxel).
// Why: publishing went voxel by voxel (find the next set bit, branch on hit / known / changed),
// ~15 instructions per updated voxel; a frame updates ~1M voxels, mostly in dense runs (2x2x2
// cells of coarse clearing), so whole groups of four cost a few instructions each.
// Exactly the scalar rule, with the same float operations in the same order (so the same bits):
//   before = known ? value : 0;  after = hit ? model.applyHit(before) : model.applyMiss(before);
//   written (and reported changed) where updated and (!known or after != before).
// Units: log-odds (log_odds.h). Threads: a pure function of its arguments and the 64 values.
#pragma once

#include <bit>
#include <cstdint>

#include "mapping/detail/simd_target.h"
#include "mapping/log_odds.h"

// The AVX2 kernel: x86-64 with GCC or Clang (target attributes, __builtin_cpu_supports).
#if CENOTE_MAPPING_SSE2 && defined(__x86_64__) && defined(__GNUC__)
#define CENOTE_MAPPING_AVX2 1
#include <immintrin.h>
#else
#define CENOTE_MAPPING_AVX2 0
#endif

namespace cenote::mapping::detail {

// The rule above voxel by voxel: the portable kernel (ARM, CENOTE_FORCE_SCALAR); tests compare
// publishWord against it. Arguments and result as publishWord's.
inline uint64_t publishWordScalar(float* values, uint64_t known, uint64_t update, uint64_t hits,
                                  const LogOddsModel& model) {
  uint64_t changed = 0;
  for (uint64_t rest = update; rest != 0; rest &= rest - 1) {
    const int i = std::countr_zero(rest);
    const uint64_t bit = uint64_t{1} << i;
    const bool is_known = (known & bit) != 0;
    const float before = is_known ? values[i] : 0.0f;
    const float after = (hits & bit) != 0 ? model.applyHit(before) : model.applyMiss(before);
    if (!is_known || after != before) {
      values[i] = after;
      changed |= bit;
    }
  }
  return changed;
}

#if CENOTE_MAPPING_SSE2

// All-ones lanes for the set bits of a 4-bit group (bit i -> lane i).
inline __m128 laneMask(unsigned bits4) {
  alignas(16) static constexpr uint32_t kLanes[16][4] = {
      {0, 0, 0, 0},     {~0u, 0, 0, 0},     {0, ~0u, 0, 0},     {~0u, ~0u, 0, 0},    {0, 0, ~0u, 0},   {~0u, 0, ~0u, 0},
      {0, ~0u, ~0u, 0}, {~0u, ~0u, ~0u, 0}, {0, 0, 0, ~0u},     {~0u, 0, 0, ~0u},    {0, ~0u, 0, ~0u}, {~0u, ~0u, 0, ~0u},
      {0, 0, ~0u, ~0u}, {~0u, 0, ~0u, ~0u}, {0, ~0u, ~0u, ~0u}, {~0u, ~0u, ~0u, ~0u}};
  return _mm_load_ps(reinterpret_cast<const float*>(kLanes[bits4 & 15]));
}

inline __m128 select(__m128 mask, __m128 if_set, __m128 if_clear) {
  return _mm_or_ps(_mm_and_ps(mask, if_set), _mm_andnot_ps(mask, if_clear));
}

// Applies the updates of one word to values[0..63], four voxels per SSE2 instruction. update:
// voxels to update (free or hit); hits: those hit (hit wins where both); known: observed before.
// @return the changed voxels.
inline uint64_t publishWordSse2(float* values, uint64_t known, uint64_t update, uint64_t hits, const LogOddsModel& model) {
  const __m128 hit = _mm_set1_ps(model.hit), miss = _mm_set1_ps(model.miss);
  const __m128 clamp_max = _mm_set1_ps(model.clamp_max), clamp_min = _mm_set1_ps(model.clamp_min);
  uint64_t changed = 0;
  for (int g = 0; g < 16 && (update >> (4 * g)) != 0; ++g) {
    const unsigned to_update = static_cast<unsigned>(update >> (4 * g)) & 15;
    if (to_update == 0) continue;
    const __m128 is_known = laneMask(static_cast<unsigned>(known >> (4 * g)));
    const __m128 is_hit = laneMask(static_cast<unsigned>(hits >> (4 * g)));
    const __m128 value = _mm_loadu_ps(values + 4 * g);
    const __m128 before = _mm_and_ps(is_known, value);  // +0 where unknown, as the scalar 0.0f
    const __m128 plus_hit = _mm_add_ps(before, hit);
    const __m128 plus_miss = _mm_add_ps(before, miss);
    const __m128 after = select(is_hit, select(_mm_cmpgt_ps(plus_hit, clamp_max), clamp_max, plus_hit),
                                select(_mm_cmplt_ps(plus_miss, clamp_min), clamp_min, plus_miss));
    const __m128 differs = _mm_or_ps(_mm_cmpneq_ps(after, before), _mm_xor_ps(is_known, laneMask(15)));
    const __m128 write = _mm_and_ps(laneMask(to_update), differs);
    _mm_storeu_ps(values + 4 * g, select(write, after, value));
    changed |= static_cast<uint64_t>(_mm_movemask_ps(write)) << (4 * g);
  }
  return changed;
}

#if CENOTE_MAPPING_AVX2

// All-ones lanes for the set bits of an 8-bit group (bit i -> lane i).
[[gnu::target("avx2")]] inline __m256 laneMask8(unsigned bits8) {
  const __m256i lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i set = _mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits8 & 255)), lane_bits);
  return _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane_bits));
}

// publishWordSse2 eight voxels per AVX2 instruction, for CPUs with AVX2 (publishWord chooses at
// run time): the same additions and comparisons lane by lane (no product, so nothing a compiler
// could fuse), and blends of all-ones or all-zero masks, which select as and / andnot / or do: the
// same bits. Why: publishing is the serial part of an integration (on one thread, under the grid's
// lock), and this kernel was most of it.
[[gnu::target("avx2")]] inline uint64_t publishWordAvx2(float* values, uint64_t known, uint64_t update, uint64_t hits,
                                                        const LogOddsModel& model) {
  const __m256 hit = _mm256_set1_ps(model.hit), miss = _mm256_set1_ps(model.miss);
  const __m256 clamp_max = _mm256_set1_ps(model.clamp_max), clamp_min = _mm256_set1_ps(model.clamp_min);
  const __m256 all = laneMask8(255);
  uint64_t changed = 0;
  for (int g = 0; g < 8 && (update >> (8 * g)) != 0; ++g) {
    const unsigned to_update = static_cast<unsigned>(update >> (8 * g)) & 255;
    if (to_update == 0) continue;
    const __m256 is_known = laneMask8(static_cast<unsigned>(known >> (8 * g)));
    const __m256 is_hit = laneMask8(static_cast<unsigned>(hits >> (8 * g)));
    const __m256 value = _mm256_loadu_ps(values + 8 * g);
    const __m256 before = _mm256_and_ps(is_known, value);  // +0 where unknown, as the scalar 0.0f
    const __m256 plus_hit = _mm256_add_ps(before, hit);
    const __m256 plus_miss = _mm256_add_ps(before, miss);
    const __m256 after_hit = _mm256_blendv_ps(plus_hit, clamp_max, _mm256_cmp_ps(plus_hit, clamp_max, _CMP_GT_OS));
    const __m256 after_miss = _mm256_blendv_ps(plus_miss, clamp_min, _mm256_cmp_ps(plus_miss, clamp_min, _CMP_LT_OS));
    const __m256 after = _mm256_blendv_ps(after_miss, after_hit, is_hit);
    const __m256 differs = _mm256_or_ps(_mm256_cmp_ps(after, before, _CMP_NEQ_UQ), _mm256_xor_ps(is_known, all));
    const __m256 write = _mm256_and_ps(laneMask8(to_update), differs);
    _mm256_storeu_ps(values + 8 * g, _mm256_blendv_ps(value, after, write));
    changed |= static_cast<uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(write))) << (8 * g);
  }
  return changed;
}
#endif

// Applies the updates of one word to values[0..63] (arguments and result as publishWordSse2):
// publishWordAvx2 where the CPU has AVX2, else publishWordSse2.
inline uint64_t publishWord(float* values, uint64_t known, uint64_t update, uint64_t hits, const LogOddsModel& model) {
#if CENOTE_MAPPING_AVX2
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  if (has_avx2) return publishWordAvx2(values, known, update, hits, model);
#endif
  return publishWordSse2(values, known, update, hits, model);
}
#else
// As above, voxel by voxel.
inline uint64_t publishWord(float* values, uint64_t known, uint64_t update, uint64_t hits, const LogOddsModel& model) {
  return publishWordScalar(values, known, update, hits, model);
}
#endif

}  // namespace cenote::mapping::detail
