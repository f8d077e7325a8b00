#include "eval/map/map_comparison.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "mapping/io/map_io.h"
#include "tests/eval/eval_test_util.h"

namespace cenote::eval {
namespace {

// Rays from the origin to a 1 m x 1 m wall wall_z_m ahead, optionally with a post in front of it.
std::unique_ptr<mapping::OccupancyMap> wallMap(double voxel_m, bool post, float wall_z_m = 2.05f) {
  mapping::MapConfig config;
  config.voxel_size_m = voxel_m;
  auto map = std::make_unique<mapping::OccupancyMap>(config);
  PointBatch batch;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 20; ++j) batch.points.emplace_back(-0.5f + 0.05f * i, -0.5f + 0.05f * j, wall_z_m);
  }
  if (post) batch.points.emplace_back(0.3f, 0.3f, 1.0f);
  map->integrate(batch);
  return map;
}

TEST(MapComparison, MapAgainstItselfAgreesEverywhere) {
  const auto map = wallMap(0.1, false);
  const OccupancyConfusion c = compareMaps(*map, *map);
  const OccupancyAgreement a = summarizeAgreement(c);
  const mapping::MapStats stats = map->stats();
  EXPECT_EQ(c.at(Occupancy::kOccupied, Occupancy::kOccupied), static_cast<int64_t>(stats.occupied));
  EXPECT_EQ(c.at(Occupancy::kFree, Occupancy::kFree), static_cast<int64_t>(stats.free));
  EXPECT_GT(stats.occupied, 0u);
  EXPECT_DOUBLE_EQ(a.agreement, 1.0);
  EXPECT_DOUBLE_EQ(a.agreement_within_voxel, 1.0);
  EXPECT_DOUBLE_EQ(a.occupied_iou, 1.0);
}

// The wall one voxel further: its voxels and the free space before it differ, but every state of
// one map is found within a voxel in the other. Two voxels further: the old wall lies in free
// space with no occupied voxel next to it.
TEST(MapComparison, WithinAVoxelForgivesAOneVoxelShiftOnly) {
  const auto near = wallMap(0.1, false, 2.05f);
  const OccupancyAgreement one = summarizeAgreement(compareMaps(*wallMap(0.1, false, 2.15f), *near));
  EXPECT_LT(one.agreement, 0.95);
  EXPECT_DOUBLE_EQ(one.agreement_within_voxel, 1.0);
  const OccupancyConfusion two_table = compareMaps(*wallMap(0.1, false, 2.25f), *near);
  const OccupancyAgreement two = summarizeAgreement(two_table);
  EXPECT_LT(two.agreement_within_voxel, 1.0);
  // The old wall's voxels (occupied against free, 400 of them): no occupied voxel within one.
  EXPECT_LE(two_table.within_voxel, two.known_either - two_table.at(Occupancy::kFree, Occupancy::kOccupied));
}

TEST(MapComparison, EmptyEstimateHasZeroAgreementAndRecall) {
  const auto map = wallMap(0.1, false);
  mapping::MapConfig config;
  config.voxel_size_m = 0.1;
  const mapping::OccupancyMap empty(config);
  const OccupancyAgreement a = summarizeAgreement(compareMaps(empty, *map));
  EXPECT_EQ(a.agreement, 0.0);
  EXPECT_EQ(a.occupied_recall, 0.0);
  EXPECT_TRUE(std::isnan(a.occupied_precision));
}

TEST(MapComparison, ExtraObstacleLowersPrecisionOnly) {
  const auto with_post = wallMap(0.1, true);
  const auto without = wallMap(0.1, false);
  const OccupancyAgreement a = summarizeAgreement(compareMaps(*with_post, *without));
  EXPECT_LT(a.occupied_precision, 1.0);
  EXPECT_DOUBLE_EQ(a.occupied_recall, 1.0);
  EXPECT_LT(a.agreement, 1.0);
  // The post stands in the other map's free space, no occupied voxel within one of it.
  EXPECT_LT(a.agreement_within_voxel, 1.0);
}

TEST(MapComparison, FilesCompareAsInMemoryAndVoxelSizesMustMatch) {
  test::TempDir dir;
  const auto map = wallMap(0.1, true);
  mapping::saveMap(*map, dir / "a.vdb");
  mapping::saveMap(*wallMap(0.1, false), dir / "b.vdb");
  mapping::saveMap(*wallMap(0.2, false), dir / "c.vdb");
  const MapComparison files = compareMapFiles(dir / "a.vdb", dir / "b.vdb");
  EXPECT_GT(files.confusion.at(Occupancy::kOccupied, Occupancy::kOccupied), 0);  // premise: not two empty tables
  EXPECT_EQ(files.confusion.counts, compareMaps(*map, *wallMap(0.1, false)).counts);
  EXPECT_DOUBLE_EQ(files.voxel_size_m, 0.1);
  EXPECT_THROW(compareMapFiles(dir / "a.vdb", dir / "c.vdb"), Error);
  EXPECT_THROW(compareMapFiles(dir / "absent.vdb", dir / "b.vdb"), Error);
}

}  // namespace
}  // namespace cenote::eval
