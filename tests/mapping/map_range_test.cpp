// map_range.h: the one range check of boxes, and the regions (clear box, clear sphere) that are
// clipped to the range, against brute force over every known voxel.
#include "mapping/map_range.h"

#include <gtest/gtest.h>

#include <vector>

#include "common/error.h"
#include "mapping/occupancy_map.h"
#include "tests/mapping/support/ray_maps.h"

namespace cenote::mapping {
namespace {

Aabb box(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) { return Aabb{min_m, max_m}; }

TEST(MapRange, VoxelsWhoseCentreLiesInTheBox) {
  // 0.1 m voxels: voxel i's centre is 0.1 i + 0.05.
  const BoxVoxels one = voxelsOfBox(box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.1)), 0.1, "box");
  EXPECT_TRUE(one.within_range);
  EXPECT_EQ(one.voxels.min, VoxelIndex(0, 0, 0));
  EXPECT_EQ(one.voxels.max, VoxelIndex(0, 0, 0));
  EXPECT_EQ(one.count(), 1u);
  const BoxVoxels none = voxelsOfBox(box(Eigen::Vector3d::Constant(0.06), Eigen::Vector3d::Constant(0.14)), 0.1, "box");
  EXPECT_TRUE(none.voxels.isEmpty());
  EXPECT_EQ(none.count(), 0u);
  const BoxVoxels neg = voxelsOfBox(box(Eigen::Vector3d(-0.24, -0.05, 0), Eigen::Vector3d(0.05, 0.05, 0.3)), 0.1, "b");
  EXPECT_EQ(neg.voxels.min, VoxelIndex(-2, -1, 0));
  EXPECT_EQ(neg.voxels.max, VoxelIndex(0, 0, 2));
  EXPECT_EQ(neg.count(), 3u * 2u * 3u);
  EXPECT_EQ(voxelsOfBox(Aabb{}, 0.1, "box").count(), 0u);
  EXPECT_TRUE(voxelsOfBox(Aabb{}, 0.1, "box").within_range);
}

// A box from 0 to 1e30 m once converted 1e30 / s to int (undefined; INT_MIN on x86), so it
// held no voxel. Now it holds every voxel from 0 to the range's edge, and says it reaches beyond.
TEST(MapRange, HugeFiniteBoxIsClippedToTheRangeNotWrapped) {
  const double s = 0.05;
  const BoxVoxels half = voxelsOfBox(box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(1e30)), s, "box");
  EXPECT_FALSE(half.within_range);
  EXPECT_EQ(half.voxels.min, VoxelIndex(0, 0, 0));
  EXPECT_EQ(half.voxels.max, VoxelIndex::Constant(kMaxVoxelIndex));
  const BoxVoxels all = voxelsOfBox(box(Eigen::Vector3d::Constant(-1e300), Eigen::Vector3d::Constant(1e300)), s, "box");
  EXPECT_EQ(all.voxels.min, VoxelIndex::Constant(-kMaxVoxelIndex));
  EXPECT_EQ(all.voxels.max, VoxelIndex::Constant(kMaxVoxelIndex));
  EXPECT_EQ(all.count(),
            static_cast<uint64_t>(2 * kMaxVoxelIndex + 1) * (2 * kMaxVoxelIndex + 1) * (2 * kMaxVoxelIndex + 1));
  const BoxVoxels beyond = voxelsOfBox(box(Eigen::Vector3d::Constant(1e30), Eigen::Vector3d::Constant(2e30)), s, "box");
  EXPECT_FALSE(beyond.within_range);
  EXPECT_TRUE(beyond.voxels.isEmpty());
  // The edge itself: within the range up to +-kMaxVoxelIndex * s.
  const double r = mapRange_m(s);
  EXPECT_DOUBLE_EQ(r, kMaxVoxelIndex * s);
  EXPECT_TRUE(voxelsOfBox(box(Eigen::Vector3d::Constant(-r), Eigen::Vector3d::Constant(r)), s, "box").within_range);
  EXPECT_FALSE(voxelsOfBox(box(Eigen::Vector3d::Constant(-r), Eigen::Vector3d(r, r, r * 1.001)), s, "b").within_range);
  EXPECT_EQ(mapRangeText(s), "the map's range, +-52428 m on each axis");
}

TEST(MapRange, NonFiniteBoxIsAnErrorNamingIt) {
  try {
    voxelsOfBox(box(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, std::nan(""), 1)), 0.1, "clear box");
    ADD_FAILURE() << "a NaN corner was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "clear box must be finite");
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidArgument);
  }
}

// Rays from the origin in all directions, 0.1 m voxels: known voxels on both sides of every plane
// through the origin.
std::unique_ptr<OccupancyMap> star() {
  std::vector<Eigen::Vector3f> ends;
  for (int i = -4; i <= 4; ++i) {
    for (int j = -4; j <= 4; ++j) {
      ends.emplace_back(2.0f, 0.4f * i, 0.4f * j);
      ends.emplace_back(-2.0f, 0.4f * i, 0.4f * j);
      ends.emplace_back(0.4f * i, 2.0f, 0.4f * j);
      ends.emplace_back(0.4f * i, -2.0f, 0.4f * j);
    }
  }
  return test::mapOfRays(0.1, {test::rays(Eigen::Vector3d(0.01, 0.02, 0.03), std::move(ends))});
}

struct KnownVoxel {
  VoxelIndex ijk;
  VoxelState state;
};

std::vector<KnownVoxel> knownVoxels(const OccupancyMap& map) {
  std::vector<KnownVoxel> out;
  const auto acc = map.constAccessor();
  for (const BlockIndex& block : acc.knownBlocks()) {
    for (int o = 0; o < kBlockVoxels; ++o) {
      const VoxelIndex ijk = voxelOfOffset(block, o);
      const VoxelState state = acc.state(ijk);
      if (state != VoxelState::kUnknown) out.push_back({ijk, state});
    }
  }
  return out;
}

// Each voxel known before: unknown after when `cleared` says so of its centre, else unchanged.
template <typename Cleared>
void expectCleared(const std::vector<KnownVoxel>& before, const OccupancyMap& after, Cleared&& cleared, uint64_t& n_cleared,
                   uint64_t& n_kept) {
  const auto acc = after.constAccessor();
  for (const KnownVoxel& v : before) {
    const bool gone = cleared(after.toPoint(v.ijk));
    const VoxelState want = gone ? VoxelState::kUnknown : v.state;
    EXPECT_EQ(acc.state(v.ijk), want) << "voxel (" << v.ijk.transpose() << ")";
    (gone ? n_cleared : n_kept) += 1;
  }
}

TEST(MapRange, ClearBoxReachingFarBeyondTheRangeClearsItsHalf) {
  auto map = star();
  const auto before = knownVoxels(*map);
  ASSERT_GT(before.size(), 1000u);
  // Every voxel whose centre has y >= 0.
  const Aabb half = box(Eigen::Vector3d(-1e30, 0, -1e30), Eigen::Vector3d::Constant(1e30));
  map->clearBox(half);
  uint64_t cleared = 0, kept = 0;
  expectCleared(
      before, *map, [](const Eigen::Vector3d& c) { return c.y() >= 0.0; }, cleared, kept);
  EXPECT_GT(cleared, 300u);
  EXPECT_GT(kept, 300u);
  EXPECT_EQ(knownVoxels(*map).size(), kept);
}

TEST(MapRange, ClearSphereOfHugeRadiusClearsAllAndFarAwayNothing) {
  auto map = star();
  const auto before = knownVoxels(*map);
  map->clearSphere(Eigen::Vector3d(1e30, 0, 0), 1.0);  // nothing within
  EXPECT_EQ(knownVoxels(*map).size(), before.size());
  // Centred on +1e30 x with radius 1e30: every voxel with x > 0 (to double precision).
  map->clearSphere(Eigen::Vector3d(1e30, 0, 0), 1e30);
  uint64_t cleared = 0, kept = 0;
  expectCleared(
      before, *map, [](const Eigen::Vector3d& c) { return c.x() > 0.0; }, cleared, kept);
  EXPECT_GT(cleared, 300u);
  EXPECT_GT(kept, 300u);
  map->clearSphere(Eigen::Vector3d::Zero(), 1e30);
  EXPECT_TRUE(knownVoxels(*map).empty());
}

}  // namespace
}  // namespace cenote::mapping
