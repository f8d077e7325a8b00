// RayBatch (integration/ray_batch.h): early stopping marches a fraction of whole rays' steps, makes
// free only voxels whole rays make free, and the same ones for any thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>

#include "mapping/integration/ray_batch.h"
#include "mapping/map_config.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping {
namespace {

constexpr double kVoxelM = 0.05;
constexpr double kMaxRangeM = 10.0;

// bench/map_bench's second view: an 800 x 600 camera 2 m above a sloping sea floor with rocks,
// looking 14 degrees down, 1 cm depth noise; pixels that see nothing within 12 m give no point.
PointBatch seaFloorView() {
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -2.0), Eigen::Vector3d(0.03, 0.05, 1.0).normalized()});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0.0, 14.0), y(-5.0, 5.0), r(0.2, 1.0);
  for (int i = 0; i < 40; ++i) scene.spheres.push_back({Eigen::Vector3d(x(rng), y(rng), -2.0), r(rng)});
  const PinholeCamera camera{.width = 800, .height = 600, .fx = 600.0, .fy = 600.0, .cx = 399.5, .cy = 299.5};
  const double pitch = 0.24;
  const Eigen::Vector3d position(0.3, 0.05, 0.0);
  const Eigen::Vector3d target = position + Eigen::Vector3d(std::cos(pitch), 0.0, -std::sin(pitch));
  return test::renderBatch(scene, camera, test::lookAt(position, target), 12.0, 0.01, 101);
}

// The free and hit masks of a build, by block.
using Masks = std::map<uint64_t, BlockMasks>;
Masks masksOf(const BatchUpdates& updates) {
  Masks out;
  for (size_t i = 0; i < updates.numBlocks(); ++i) out[detail::packIndex(updates.block(i))] = updates.masks(i);
  return out;
}

struct Count {
  size_t free = 0;            // free voxels of `part`
  size_t free_not_whole = 0;  // ... that `whole` does not hold free
  size_t whole_free = 0;      // free voxels of `whole`
  bool same_hits = true;      // every block of `part` has the hits of `whole`'s
  size_t hits = 0, whole_hits = 0;
};
Count compare(const Masks& part, const Masks& whole) {
  Count c;
  for (const auto& [key, m] : whole) {
    for (uint64_t w : m.free) c.whole_free += static_cast<size_t>(__builtin_popcountll(w));
    for (uint64_t w : m.hit) c.whole_hits += static_cast<size_t>(__builtin_popcountll(w));
  }
  for (const auto& [key, m] : part) {
    const auto it = whole.find(key);
    for (int w = 0; w < 8; ++w) {
      const uint64_t whole_free = it == whole.end() ? 0 : it->second.free[w];
      const uint64_t whole_hit = it == whole.end() ? 0 : it->second.hit[w];
      c.free += static_cast<size_t>(__builtin_popcountll(m.free[w]));
      c.free_not_whole += static_cast<size_t>(__builtin_popcountll(m.free[w] & ~whole_free));
      c.same_hits = c.same_hits && m.hit[w] == whole_hit;
      c.hits += static_cast<size_t>(__builtin_popcountll(m.hit[w]));
    }
  }
  return c;
}

// Early stopping (the default run of 32, rays in 16 interleaved passes within each of 8 chunks)
// against whole rays on the sea floor view: at most 40 % of their steps (2323967 of 6821284 here,
// 34 %; image order in 16 chunks with a run of 16, the scheme before, took 45 %), a subset of their
// free voxels with at most 0.15 % of them left unknown (426 of 478047 here, 0.089 %; before:
// 0.11 %), the same hits.
TEST(RayBatch, EarlyStopMarchesUnder40PercentOfWholeRaysStepsAndKeepsTheirFreeVoxelsBut0Point15Percent) {
  const PointBatch view = seaFloorView();
  ASSERT_GT(view.points.size(), 200000u);
  RayBatch fast, whole;
  fast.build(view, kVoxelM, kMaxRangeM, 1, MapConfig().ray_stop_run);
  whole.build(view, kVoxelM, kMaxRangeM, 1, 0);
  const Count c = compare(masksOf(fast.updates()), masksOf(whole.updates()));
  ASSERT_GT(c.whole_free, 100000u);
  EXPECT_LE(fast.numSteps(), whole.numSteps() * 2 / 5) << fast.numSteps() << " steps, whole rays " << whole.numSteps();
  EXPECT_EQ(c.free_not_whole, 0u) << "free with early stopping but not with whole rays";
  EXPECT_GE(c.free, c.whole_free - c.whole_free * 3 / 2000) << c.free << " free, whole rays " << c.whole_free;
  EXPECT_TRUE(c.same_hits);
  EXPECT_EQ(c.hits, c.whole_hits);
  std::cout << "early stop: " << fast.numSteps() << " steps (whole rays " << whole.numSteps() << "), " << c.free
            << " free voxels (whole rays " << c.whole_free << ")\n";
}

// The chunks (fixed in number) and their rays' order depend on the points alone: 1 and 2 threads
// march the same steps into the same masks.
TEST(RayBatch, OneAndTwoThreadsMarchTheSameStepsIntoTheSameMasks) {
  const PointBatch view = seaFloorView();
  RayBatch one, two;
  one.build(view, kVoxelM, kMaxRangeM, 1, MapConfig().ray_stop_run);
  two.build(view, kVoxelM, kMaxRangeM, 2, MapConfig().ray_stop_run);
  EXPECT_EQ(one.numSteps(), two.numSteps());
  const Masks a = masksOf(one.updates()), b = masksOf(two.updates());
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [key, m] : a) {
    const auto it = b.find(key);
    ASSERT_NE(it, b.end()) << "block " << key << " only on 1 thread";
    EXPECT_EQ(m.free, it->second.free) << "block " << key;
    EXPECT_EQ(m.hit, it->second.hit) << "block " << key;
  }
}

}  // namespace
}  // namespace cenote::mapping
