// map_query.h, BatchControl: the work budget counted before a batch runs, and the slices between
// which the map's shared lock is released (a writer gets in; later items see its change).
#include <gtest/gtest.h>

#include <random>
#include <thread>

#include "common/error.h"
#include "mapping/integration/voxel_ray.h"
#include "mapping/query/map_query.h"

namespace cenote::mapping {
namespace {

std::unique_ptr<OccupancyMap> emptyMap() {
  MapConfig c;
  c.voxel_size_m = 0.1;
  return std::make_unique<OccupancyMap>(c);
}

// A segment's bound is the number of voxels the walk passes from end voxel to end voxel; a
// capsule's is at least the voxels whose centre lies within its radius (the sweep examines each).
TEST(MapQueryBudget, VisitBoundCoversWhatAQueryVisits) {
  const double s = 0.1;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int n = 0; n < 200; ++n) {
    const SegmentQuery q{Eigen::Vector3d(u(rng), u(rng), u(rng)), Eigen::Vector3d(u(rng), u(rng), u(rng)), 0.0};
    uint64_t visited = 0;
    walkVoxels(q.start_m, q.end_m, s, true, [&](const VoxelIndex&) { return ++visited, true; });
    const VoxelIndex d = (toVoxel(q.end_m, s) - toVoxel(q.start_m, s)).cwiseAbs();
    EXPECT_EQ(visitBound(q, s), static_cast<uint64_t>(d.sum() + 1)) << "segment " << n;
    EXPECT_LE(visited, visitBound(q, s)) << "segment " << n;
  }
  for (int n = 0; n < 50; ++n) {
    const SegmentQuery q{Eigen::Vector3d(u(rng), u(rng), u(rng)), Eigen::Vector3d(u(rng), u(rng), u(rng)),
                         0.05 + 0.1 * (n % 5)};
    const Aabb b = boundsOf(q);
    const VoxelIndex lo = toVoxel(b.min_m, s), hi = toVoxel(b.max_m, s);
    uint64_t inside = 0;
    const Eigen::Vector3d d = q.end_m - q.start_m;
    for (int x = lo.x(); x <= hi.x(); ++x) {
      for (int y = lo.y(); y <= hi.y(); ++y) {
        for (int z = lo.z(); z <= hi.z(); ++z) {
          const Eigen::Vector3d c = voxelCentre(VoxelIndex(x, y, z), s);
          const double t = std::clamp((c - q.start_m).dot(d) / d.squaredNorm(), 0.0, 1.0);
          inside += (q.start_m + t * d - c).norm() <= q.radius_m;
        }
      }
    }
    const uint64_t box = static_cast<uint64_t>(((hi - lo).array() + 1).prod());
    EXPECT_GE(visitBound(q, s), inside) << "capsule " << n;
    EXPECT_LE(visitBound(q, s), box) << "capsule " << n;
  }
  // A long diagonal capsule: far fewer than its bounding box's voxels.
  const SegmentQuery diagonal{Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(10.0), 0.2};
  EXPECT_LT(visitBound(diagonal, s), 101u * 101u * 101u / 10u);
}

TEST(MapQueryBudget, BatchBeyondTheBudgetIsRefusedNamingIt) {
  const auto map = emptyMap();
  // 0.1 m voxels: from voxel 0 to voxel 99 along x, 100 voxels each.
  const std::vector<SegmentQuery> segments(
      30, SegmentQuery{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(9.95, 0.05, 0.05), 0.0});
  BatchControl control;
  control.budget_name = "server.limits.max_query_voxels";
  control.max_voxels = 3000;
  EXPECT_EQ(checkSegments(*map, segments, false, control).size(), 30u);  // exactly the budget
  control.max_voxels = 2999;
  try {
    checkSegments(*map, segments, false, control);
    ADD_FAILURE() << "a batch of 3000 voxels ran on a budget of 2999";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kResourceExhausted);
    EXPECT_EQ(std::string(e.what()), "map query: 30 segments may visit up to 3000 voxels, more than the budget "
                                     "server.limits.max_query_voxels = 2999");
  }
  const std::vector<Aabb> boxes(4, Aabb{Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 1.0, 1.0)});  // 10^3 each
  control.max_voxels = 3999;
  try {
    queryBoxes(*map, boxes, control);
    ADD_FAILURE() << "4000 box voxels ran on a budget of 3999";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kResourceExhausted);
    EXPECT_EQ(std::string(e.what()), "map query: 4 boxes may visit up to 4000 voxels, more than the budget "
                                     "server.limits.max_query_voxels = 3999");
  }
  // A ray to the edge of the map's range: about 1 M voxels at 0.1 m.
  control.max_voxels = 1000000;
  try {
    raycast(*map, {Ray{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d::UnitX()}}, 1e9, false, control);
    ADD_FAILURE() << "a ray across the map's range ran on a budget of 1e6";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "map query: 1 rays may visit up to " + std::to_string(kMaxVoxelIndex) +
                                         " voxels, more than the budget server.limits.max_query_voxels = 1000000");
  }
}

// Slices of slice_voxels: between_slices runs between them with the items done so far, and what
// it throws ends the batch.
TEST(MapQueryBudget, BetweenSlicesRunsAfterEachSliceAndMayEndTheBatch) {
  const auto map = emptyMap();
  const std::vector<SegmentQuery> segments(
      10, SegmentQuery{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(0.95, 0.05, 0.05), 0.0});  // 10 voxels
  BatchControl control;
  control.slice_voxels = 25;  // three segments a slice
  std::vector<size_t> calls;
  control.between_slices = [&](size_t done) { calls.push_back(done); };
  EXPECT_EQ(checkSegments(*map, segments, false, control).size(), 10u);
  EXPECT_EQ(calls, (std::vector<size_t>{3, 6, 9}));
  calls.clear();
  control.between_slices = [&](size_t done) {
    calls.push_back(done);
    if (done >= 6) throw std::runtime_error("deadline");
  };
  EXPECT_THROW(checkSegments(*map, segments, false, control), std::runtime_error);
  EXPECT_EQ(calls, (std::vector<size_t>{3, 6}));
}

// A free corridor along x from (0.05, 0.05, 0.05), ending in a hit at x = 2.05.
std::unique_ptr<OccupancyMap> corridorMap() {
  auto map = emptyMap();
  PointBatch floor;
  floor.origin = Eigen::Vector3d(0.05, 0.05, 0.05);
  floor.points = {Eigen::Vector3f(2.05f, 0.05f, 0.05f)};
  map->integrate(floor);
  return map;
}

// Before items[4]: a wall voxel at x = 1.05 across the corridor, integrated by another thread, which
// would wait for ever if the batch still held the map's shared lock.
BatchControl wallAfterFourItems(OccupancyMap& map, int& writes) {
  BatchControl control;
  control.slice_voxels = 40;  // two items of 20 voxels a slice
  control.between_slices = [&map, &writes](size_t done) {
    if (done != 4) return;
    ++writes;
    std::thread writer([&map] {
      PointBatch wall;
      wall.origin = Eigen::Vector3d(1.05, 0.05, 2.05);
      wall.points = {Eigen::Vector3f(1.05f, 0.05f, 0.05f)};
      map.integrate(wall);
    });
    writer.join();
  };
  return control;
}

// The lock is not held between slices: a writer that starts there completes, and the items after
// it see its change, each item one state of the map.
TEST(MapQueryBudget, WriterGetsInBetweenSlicesAndLaterItemsSeeItsChange) {
  {
    auto map = corridorMap();
    int writes = 0;
    const SegmentQuery through{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(1.95, 0.05, 0.05), 0.0};
    const auto r = checkSegments(*map, std::vector<SegmentQuery>(8, through), false, wallAfterFourItems(*map, writes));
    EXPECT_EQ(writes, 1);
    for (size_t i = 0; i < r.size(); ++i) EXPECT_EQ(r[i].hit, i >= 4) << "segment " << i;
    EXPECT_EQ(r[4].hit_voxel, VoxelIndex(10, 0, 0));
  }
  {
    auto map = corridorMap();
    int writes = 0;
    const Aabb corridor{Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(2.0, 0.1, 0.1)};  // 20 voxels
    const auto c = queryBoxes(*map, std::vector<Aabb>(8, corridor), wallAfterFourItems(*map, writes));
    EXPECT_EQ(writes, 1);
    for (size_t i = 0; i < c.size(); ++i) {
      EXPECT_EQ(c[i].occupied, i >= 4 ? 1u : 0u) << "box " << i;
      EXPECT_EQ(c[i].total(), 20u) << "box " << i;
    }
  }
}

}  // namespace
}  // namespace cenote::mapping
