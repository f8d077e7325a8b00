// cluster_split.h: the moments of a block's run of frontier voxels (packed per-slice sums) against
// the same sums taken voxel by voxel from their definitions.
#include "mapping/frontier/cluster_split.h"

#include <gtest/gtest.h>

#include <random>

namespace cenote::mapping::detail {
namespace {

TEST(ClusterSplit, BlockRunMomentsEqualVoxelByVoxelSums) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    // From a single voxel up to a full block, and any face set (all six unknown included).
    BlockMask bits{};
    std::array<uint8_t, kBlockVoxels> faces{};
    const double density = trial == 0 ? 1.0 : std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    for (int o = 0; o < kBlockVoxels; ++o) {
      if (std::uniform_real_distribution<double>(0.0, 1.0)(rng) >= density) continue;
      bits[o >> 6] |= 1ull << (o & 63);
      faces[o] = static_cast<uint8_t>(trial == 0 ? 63 : rng() & 63);
    }
    if (isEmpty(bits)) bits[3] = 1ull << 17;
    int64_t n = 0, sum[3] = {}, sum2[6] = {}, dir[3][3] = {};
    int lo[3] = {7, 7, 7}, hi[3] = {0, 0, 0};
    for (int o = 0; o < kBlockVoxels; ++o) {
      if (((bits[o >> 6] >> (o & 63)) & 1) == 0) continue;
      const int v[3] = {o >> 6, (o >> 3) & 7, o & 7};
      ++n;
      for (int i = 0; i < 3; ++i) {
        sum[i] += v[i];
        lo[i] = std::min(lo[i], v[i]);
        hi[i] = std::max(hi[i], v[i]);
      }
      const int64_t products[6] = {v[0] * v[0], v[1] * v[1], v[2] * v[2], v[0] * v[1], v[0] * v[2], v[1] * v[2]};
      for (int k = 0; k < 6; ++k) sum2[k] += products[k];
      // Direction into the unknown: +1 / -1 per axis for an unknown face, opposite faces cancel.
      int d[3], norm2 = 0;
      for (int i = 0; i < 3; ++i) {
        d[i] = ((faces[o] >> (2 * i)) & 1) - ((faces[o] >> (2 * i + 1)) & 1);
        norm2 += d[i] * d[i];
      }
      for (int i = 0; i < 3 && norm2 > 0; ++i) dir[norm2 - 1][i] += d[i];
    }
    const RunMoments m = blockRunMoments(bits, faces);
    ASSERT_EQ(m.n, n) << "trial " << trial;
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(m.sum[i], sum[i]) << "trial " << trial << ", axis " << i;
      EXPECT_EQ(m.lo[i], lo[i]) << "trial " << trial << ", axis " << i;
      EXPECT_EQ(m.hi[i], hi[i]) << "trial " << trial << ", axis " << i;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(m.dir[k][i], dir[k][i]) << "trial " << trial << ", norm2 " << k + 1;
    }
    for (int k = 0; k < 6; ++k) EXPECT_EQ(m.sum2[k], sum2[k]) << "trial " << trial << ", product " << k;
  }
}

}  // namespace
}  // namespace cenote::mapping::detail
