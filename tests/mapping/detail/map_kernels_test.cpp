// map_kernels_test.cpp: the map's vector kernels (publishWord: SSE2, and AVX2 where the CPU has
// it; occupiedMask: SSE2) give their portable scalar versions' results (what ARM runs) bit for
// bit, on random words and on every boundary value; and both follow the rules written in their
// headers.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "mapping/detail/occupied_mask.h"
#include "mapping/detail/publish_word.h"
#include "mapping/map_config.h"

namespace cenote::mapping {
namespace {

using Word = std::array<float, 64>;
using PublishKernel = uint64_t (*)(float*, uint64_t, uint64_t, uint64_t, const LogOddsModel&);
using OccupiedKernel = uint64_t (*)(const float*, uint64_t, float);

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kMax = std::numeric_limits<float>::max();

// In a scalar build (ARM, CENOTE_FORCE_SCALAR) the kernel is the scalar one: nothing to compare.
constexpr bool kHasVectorKernels = CENOTE_MAPPING_SSE2 != 0;

uint32_t bitsOf(float v) { return std::bit_cast<uint32_t>(v); }

LogOddsModel defaultModel() { return MapConfig{}.logOddsModel(); }

// A model on which every float is 0 with either sign: -0 before, +0 after is "unchanged".
LogOddsModel signedZeroModel() {
  LogOddsModel m;
  m.hit = 0.0f;
  m.miss = -0.0f;
  m.clamp_min = -0.0f;
  m.clamp_max = 0.0f;
  m.occupied = -0.0f;
  return m;
}

// Sums that overflow to infinity and clamp back to the largest float (no NaN: hit and miss are finite).
LogOddsModel extremeModel() {
  LogOddsModel m;
  m.hit = kMax;
  m.miss = -kMax;
  m.clamp_min = -kMax;
  m.clamp_max = kMax;
  m.occupied = kMax;
  return m;
}

LogOddsModel randomModel(std::mt19937_64& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  LogOddsModel m;
  m.hit = 3.0f * unit(rng);
  m.miss = -3.0f * unit(rng);
  m.clamp_min = -6.0f * unit(rng);
  m.clamp_max = 6.0f * unit(rng);
  m.occupied = m.clamp_min + (m.clamp_max - m.clamp_min) * unit(rng);
  return m;
}

// Every value a kernel compares against or lands on, a few ulps either side, and the extremes.
std::vector<float> edgeValues(const LogOddsModel& m) {
  const float denorm = std::numeric_limits<float>::denorm_min(), tiny = std::numeric_limits<float>::min();
  const std::vector<float> centres = {0.0f,
                                      -0.0f,
                                      denorm,
                                      -denorm,
                                      tiny,
                                      -tiny,
                                      kMax,
                                      -kMax,
                                      kInf,
                                      -kInf,
                                      m.clamp_min,
                                      m.clamp_max,
                                      m.occupied,
                                      m.hit,
                                      m.miss,
                                      -m.hit,
                                      -m.miss,
                                      m.clamp_max - m.hit,
                                      m.clamp_min - m.miss};
  std::vector<float> values;
  for (float c : centres) {
    float up = c, down = c;
    values.push_back(c);
    for (int ulp = 0; ulp < 3; ++ulp) {
      up = std::nextafter(up, kInf);
      down = std::nextafter(down, -kInf);
      values.push_back(up);
      values.push_back(down);
    }
  }
  return values;
}

// Half edge values, the rest log-odds in and around the clamping range or any finite float.
float randomValue(std::mt19937_64& rng, const std::vector<float>& edges, const LogOddsModel& m) {
  switch (rng() % 4) {
    case 0:
    case 1: return edges[rng() % edges.size()];
    case 2: return std::uniform_real_distribution<float>(m.clamp_min - 1.0f, m.clamp_max + 1.0f)(rng);
    default:
      for (;;) {
        const float v = std::bit_cast<float>(static_cast<uint32_t>(rng()));
        if (std::isfinite(v)) return v;
      }
  }
}

// Empty, full, random, sparse, dense, or whole groups of four (the vector kernels' lanes).
uint64_t randomMask(std::mt19937_64& rng) {
  switch (rng() % 6) {
    case 0: return 0;
    case 1: return ~uint64_t{0};
    case 2: return rng();
    case 3: return rng() & rng() & rng();
    case 4: return rng() | rng() | rng();
    default: {
      const uint64_t groups = rng();
      uint64_t mask = 0;
      for (int g = 0; g < 16; ++g) mask |= ((groups >> g) & 1) != 0 ? uint64_t{15} << (4 * g) : 0;
      return mask;
    }
  }
}

std::vector<LogOddsModel> testModels() {
  std::mt19937_64 rng(7);
  std::vector<LogOddsModel> models = {defaultModel(), signedZeroModel(), extremeModel()};
  for (int i = 0; i < 100; ++i) models.push_back(randomModel(rng));
  return models;
}

// `kernel` against publishWordScalar on random words of every test model, bit for bit.
void expectMatchesScalarBitForBit(PublishKernel kernel) {
  std::mt19937_64 rng(42);
  int compared = 0;
  for (const LogOddsModel& model : testModels()) {
    const std::vector<float> edges = edgeValues(model);
    for (int trial = 0; trial < 1000; ++trial) {
      Word vector_values, scalar_values;
      for (float& v : vector_values) v = randomValue(rng, edges, model);  // stale values where unknown too
      scalar_values = vector_values;
      const uint64_t known = randomMask(rng), update = randomMask(rng), hits = randomMask(rng);
      const uint64_t vector_changed = kernel(vector_values.data(), known, update, hits, model);
      const uint64_t scalar_changed = detail::publishWordScalar(scalar_values.data(), known, update, hits, model);
      ASSERT_EQ(vector_changed, scalar_changed) << "trial " << trial << " known " << known << " update " << update;
      for (int i = 0; i < 64; ++i) {
        ASSERT_EQ(bitsOf(vector_values[i]), bitsOf(scalar_values[i]))
            << "trial " << trial << " voxel " << i << ": " << vector_values[i] << " vs " << scalar_values[i];
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 103 * 1000);
}

// publishWord: the kernel this CPU runs.
TEST(MapKernels, PublishWordMatchesScalarBitForBit) {
  if (!kHasVectorKernels) GTEST_SKIP() << "scalar build: publishWord is publishWordScalar";
  expectMatchesScalarBitForBit(&detail::publishWord);
}

#if CENOTE_MAPPING_SSE2
TEST(MapKernels, PublishWordSse2MatchesScalarBitForBit) { expectMatchesScalarBitForBit(&detail::publishWordSse2); }
#endif

// The AVX2 kernel (chosen where the CPU has AVX2) gives the SSE2 and scalar kernels' bits.
#if CENOTE_MAPPING_SSE2 && CENOTE_MAPPING_AVX2
TEST(MapKernels, PublishWordAvx2MatchesScalarBitForBit) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "this CPU has no AVX2";
  expectMatchesScalarBitForBit(&detail::publishWordAvx2);
}
#endif

// One voxel through both kernels: the value after and whether it was reported changed.
struct VoxelOutcome {
  float value;
  bool changed;
};

VoxelOutcome publishOne(PublishKernel kernel, const LogOddsModel& model, float value, bool known, bool update, bool hit) {
  Word values{};
  const int i = 37;  // any lane of any group
  values[i] = value;
  const uint64_t bit = uint64_t{1} << i;
  const uint64_t changed = kernel(values.data(), known ? bit : 0, update ? bit : 0, hit ? bit : 0, model);
  return {values[i], (changed & bit) != 0};
}

TEST(MapKernels, PublishWordFollowsTheRule) {
  const LogOddsModel m = defaultModel();
  const LogOddsModel zero = signedZeroModel();
  for (PublishKernel kernel : {&detail::publishWord, &detail::publishWordScalar}) {
    // Unknown: from +0 whatever the stale value, always written.
    VoxelOutcome o = publishOne(kernel, m, 5.0f, false, true, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(0.0f + m.hit));
    EXPECT_TRUE(o.changed);
    o = publishOne(kernel, m, -0.0f, false, true, false);
    EXPECT_EQ(bitsOf(o.value), bitsOf(0.0f + m.miss));
    EXPECT_TRUE(o.changed);
    // Hit wins over free; a hit bit outside update is ignored.
    o = publishOne(kernel, m, 1.0f, true, true, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(1.0f + m.hit));
    o = publishOne(kernel, m, 1.0f, true, false, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(1.0f));
    EXPECT_FALSE(o.changed);
    // Clamped: at the bound nothing changes; just inside, the bound is reached.
    o = publishOne(kernel, m, m.clamp_max, true, true, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(m.clamp_max));
    EXPECT_FALSE(o.changed);
    o = publishOne(kernel, m, m.clamp_min, true, true, false);
    EXPECT_EQ(bitsOf(o.value), bitsOf(m.clamp_min));
    EXPECT_FALSE(o.changed);
    o = publishOne(kernel, m, std::nextafter(m.clamp_max, 0.0f), true, true, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(m.clamp_max));
    EXPECT_TRUE(o.changed);
    // Beyond the bounds (a loaded map's values) a hit or a miss clamps.
    o = publishOne(kernel, m, kInf, true, true, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(m.clamp_max));
    o = publishOne(kernel, m, -kMax, true, true, false);
    EXPECT_EQ(bitsOf(o.value), bitsOf(m.clamp_min));
    // -0 + 0 = +0 equals -0: known, so not written, and the sign bit stays.
    o = publishOne(kernel, zero, -0.0f, true, true, true);
    EXPECT_EQ(bitsOf(o.value), bitsOf(-0.0f));
    EXPECT_FALSE(o.changed);
    // Unknown: written as +0 + (-0) = +0 even though the value does not change.
    o = publishOne(kernel, zero, -0.0f, false, true, false);
    EXPECT_EQ(bitsOf(o.value), bitsOf(0.0f));
    EXPECT_TRUE(o.changed);
  }
}

TEST(MapKernels, OccupiedMaskMatchesScalarBitForBit) {
  if (!kHasVectorKernels) GTEST_SKIP() << "scalar build: occupiedMask is occupiedMaskScalar";
  std::mt19937_64 rng(43);
  for (const LogOddsModel& model : testModels()) {
    const std::vector<float> edges = edgeValues(model);
    // The model's threshold, and every edge value as one (values land on it exactly).
    std::vector<float> thresholds = {model.occupied};
    for (int i = 0; i < 4; ++i) thresholds.push_back(edges[rng() % edges.size()]);
    for (float occupied : thresholds) {
      for (int trial = 0; trial < 200; ++trial) {
        Word values;
        for (float& v : values) v = rng() % 3 == 0 ? occupied : randomValue(rng, edges, model);
        const uint64_t known = randomMask(rng);
        ASSERT_EQ(detail::occupiedMask(values.data(), known, occupied),
                  detail::occupiedMaskScalar(values.data(), known, occupied))
            << "threshold " << occupied << " known " << known;
      }
    }
  }
}

TEST(MapKernels, OccupiedMaskFollowsTheRule) {
  const float occupied = defaultModel().occupied;
  const std::vector<std::pair<float, bool>> cases = {{occupied, true},
                                                     {std::nextafter(occupied, -kInf), false},
                                                     {std::nextafter(occupied, kInf), true},
                                                     {-0.0f, true},
                                                     {0.0f, true},
                                                     {kInf, true},
                                                     {-kInf, false},
                                                     {kMax, true},
                                                     {-kMax, false}};
  ASSERT_EQ(bitsOf(occupied), bitsOf(0.0f));  // p = 0.5: the +-0 cases sit on the threshold
  for (OccupiedKernel kernel : {&detail::occupiedMask, &detail::occupiedMaskScalar}) {
    Word values{};
    uint64_t expected = 0;
    for (size_t i = 0; i < cases.size(); ++i) {
      values[i] = cases[i].first;
      expected |= static_cast<uint64_t>(cases[i].second) << i;
    }
    const uint64_t first_cases = (uint64_t{1} << cases.size()) - 1;
    EXPECT_EQ(kernel(values.data(), first_cases, occupied), expected);
    // Unknown voxels are never occupied, whatever their value (the rest of the word is +0 >= +0).
    EXPECT_EQ(kernel(values.data(), 0, occupied), 0u);
    EXPECT_EQ(kernel(values.data(), ~uint64_t{0}, occupied), expected | ~first_cases);
    // Against -0 as the threshold, +0 and -0 are both occupied.
    EXPECT_EQ(kernel(values.data(), uint64_t{3} << 3, -0.0f), uint64_t{3} << 3);
  }
}

}  // namespace
}  // namespace cenote::mapping
