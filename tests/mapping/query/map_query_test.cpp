#include "mapping/query/map_query.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/mapping/support/ray_maps.h"

namespace cenote::mapping {
namespace {

// A 0.1 m map: free corridor x in [0, 2) along y = z = 0.05, a wall voxel at x = 1.05, and one
// more ray along y = 0.35 ending at x = 2.05.
std::unique_ptr<OccupancyMap> corridor() {
  return test::mapOfRays(0.1, {test::rays(Eigen::Vector3d(0.05, 0.05, 0.05), {Eigen::Vector3f(1.05f, 0.05f, 0.05f)}),
                               test::rays(Eigen::Vector3d(0.05, 0.35, 0.05), {Eigen::Vector3f(2.05f, 0.35f, 0.05f)})});
}

TEST(MapQuery, VoxelStatesAndProbabilitiesInOneBatch) {
  const auto map = corridor();
  const auto r = queryVoxels(*map, {Eigen::Vector3d(0.5, 0.05, 0.05), Eigen::Vector3d(1.05, 0.05, 0.05),
                                    Eigen::Vector3d(5, 5, 5), Eigen::Vector3d(std::nan(""), 0, 0)});
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r[0].state, VoxelState::kFree);
  EXPECT_NEAR(r[0].probability, 0.4, 1e-6);
  EXPECT_EQ(r[1].state, VoxelState::kOccupied);
  EXPECT_EQ(r[2].state, VoxelState::kUnknown);
  EXPECT_EQ(r[3].state, VoxelState::kUnknown);
}

TEST(MapQuery, BoxCountsVoxelsByCentre) {
  const auto map = corridor();
  Aabb box;
  box.min_m = Eigen::Vector3d(0.0, 0.0, 0.0);
  box.max_m = Eigen::Vector3d(1.2, 0.1, 0.1);  // voxels x 0..11 along y = z = 0
  const auto counts = queryBoxes(*map, {box, Aabb{}});
  EXPECT_EQ(counts[0].free, 10u);
  EXPECT_EQ(counts[0].occupied, 1u);
  EXPECT_EQ(counts[0].unknown, 1u);
  EXPECT_TRUE(counts[0].anyOccupied());
  EXPECT_EQ(counts[1].total(), 0u);
}

TEST(MapQuery, SegmentFindsFirstOccupiedAndStopsAtUnknown) {
  const auto map = corridor();
  SegmentQuery into_wall{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(1.9, 0.05, 0.05), 0.0};
  SegmentQuery clear{Eigen::Vector3d(0.05, 0.35, 0.05), Eigen::Vector3d(1.9, 0.35, 0.05), 0.0};
  SegmentQuery into_unknown{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(0.05, 0.05, 1.0), 0.0};
  const auto r = checkSegments(*map, {into_wall, clear, into_unknown}, true);
  EXPECT_TRUE(r[0].hit);
  EXPECT_EQ(r[0].hit_voxel, VoxelIndex(10, 0, 0));
  EXPECT_NEAR(r[0].hit_distance_m, 1.0, 1e-9);
  EXPECT_TRUE(r[1].isClear());
  EXPECT_FALSE(r[1].crossed_unknown);
  EXPECT_TRUE(r[2].stopped_at_unknown);
  EXPECT_NEAR(r[2].unknown_distance_m, 0.1, 1e-9);
  const auto go_on = checkSegments(*map, {into_unknown}, false);
  EXPECT_TRUE(go_on[0].crossed_unknown);
  EXPECT_FALSE(go_on[0].stopped_at_unknown);
  EXPECT_FALSE(go_on[0].hit);
}

TEST(MapQuery, CapsuleHitsWallBesideItsAxis) {
  const auto map = corridor();
  // Along y = 0.25, between the two corridors: the wall voxel at (1.05, 0.05) is 0.2 m away.
  SegmentQuery thin{Eigen::Vector3d(0.05, 0.25, 0.05), Eigen::Vector3d(1.9, 0.25, 0.05), 0.15};
  SegmentQuery wide{Eigen::Vector3d(0.05, 0.25, 0.05), Eigen::Vector3d(1.9, 0.25, 0.05), 0.25};
  const auto r = checkSegments(*map, {thin, wide}, false);
  EXPECT_FALSE(r[0].hit);
  EXPECT_TRUE(r[1].hit);
  EXPECT_EQ(r[1].hit_voxel, VoxelIndex(10, 0, 0));
  EXPECT_TRUE(r[1].crossed_unknown);  // y = 0.15 and 0.25 were never observed
  const auto stop = checkSegments(*map, {wide}, true);
  EXPECT_TRUE(stop[0].stopped_at_unknown);
  EXPECT_FALSE(stop[0].hit);
}

TEST(MapQuery, RaycastWithinRange) {
  const auto map = corridor();
  const auto r = raycast(*map, {Ray{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(3, 0, 0)}}, 0.5, false);
  EXPECT_FALSE(r[0].hit);
  const auto far = raycast(*map, {Ray{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(3, 0, 0)}}, 5.0, false);
  EXPECT_TRUE(far[0].hit);
  EXPECT_THROW(raycast(*map, {Ray{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}}, 1.0, false), Error);
  EXPECT_THROW(checkSegments(*map, {SegmentQuery{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), -1.0}}, false), Error);
}

// Far beyond the map's range voxel indices overflow int: such queries were undefined behaviour (a
// capsule at x = -1e12 looped for ever, one at +1e12 reported no unknown voxel). Now they are
// errors naming the range, and a long ray stops at the range's edge.
TEST(MapQuery, QueriesBeyondTheMapsRangeAreErrorsNotHangs) {
  const auto map = corridor();  // 0.1 m voxels: range +-104856.8 m
  EXPECT_DOUBLE_EQ(mapRange_m(*map), kMaxVoxelIndex * 0.1);
  for (const double x : {-1e12, 1e12, 2e5}) {
    for (const double radius : {0.0, 0.1}) {
      const SegmentQuery far{Eigen::Vector3d(x, 0, 0), Eigen::Vector3d(x + 1.0, 0, 0), radius};
      try {
        checkSegments(*map, {far}, false);
        ADD_FAILURE() << "segment at x = " << x << " radius " << radius << " accepted";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("segment 0 reaches beyond the map's range, +-104856 m"), std::string::npos)
            << e.what();
      }
    }
    EXPECT_THROW(queryBoxes(*map, {Aabb{Eigen::Vector3d(x, 0, 0), Eigen::Vector3d(x + 1.0, 1, 1)}}), Error) << x;
    EXPECT_THROW(raycast(*map, {Ray{Eigen::Vector3d(x, 0, 0), Eigen::Vector3d::UnitX()}}, 1.0, false), Error) << x;
  }
  // A capsule whose bounding box holds more than 2^31 voxels (a 1 km radius at 0.1 m).
  EXPECT_THROW(checkSegments(*map, {SegmentQuery{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 1000.0}}, false),
               Error);
  // A ray longer than the range: cut at the edge, after passing the wall like a short one.
  const Ray along{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d::UnitX()};
  const auto near = raycast(*map, {along}, 5.0, false);
  const auto long_ray = raycast(*map, {along}, 1e9, false);
  EXPECT_TRUE(near[0].hit);
  EXPECT_EQ(long_ray[0].hit, near[0].hit);
  EXPECT_EQ(long_ray[0].hit_voxel, near[0].hit_voxel);
  EXPECT_DOUBLE_EQ(long_ray[0].hit_distance_m, near[0].hit_distance_m);
  // Points beyond the range are simply unknown.
  EXPECT_EQ(queryVoxels(*map, {Eigen::Vector3d(1e12, 0, 0)})[0].state, VoxelState::kUnknown);
}

}  // namespace
}  // namespace cenote::mapping
