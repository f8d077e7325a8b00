#include "mapping/frontier/frontier_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <map>
#include <string>
#include <tuple>

#include "tests/mapping/support/analytic_scene.h"
#include "tests/mapping/support/reference_cluster_split.h"

namespace cenote::mapping {
namespace {

// Six 90-degree views from one position (a cube map): everything visible from there.
std::vector<PointBatch> cubeViews(const test::Scene& scene, const Eigen::Vector3d& position) {
  PinholeCamera camera;
  camera.width = camera.height = 160;
  camera.fx = camera.fy = 80.0;
  camera.cx = camera.cy = 79.5;
  std::vector<PointBatch> views;
  const Eigen::Vector3d dirs[6] = {Eigen::Vector3d::UnitX(),  -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                   -Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),  -Eigen::Vector3d::UnitZ()};
  for (const auto& d : dirs) views.push_back(test::renderBatch(scene, camera, test::lookAt(position, position + d), 12.0));
  return views;
}

// Two 4 x 4 x 3 m rooms side by side, joined by a 1 x 2 m doorway in the wall x = 4.
test::Scene twoRooms() {
  test::Scene scene;
  const Eigen::Vector3d door_min(4.0, 1.5, 0.0), door_max(4.0, 2.5, 2.0);
  test::Box a;
  a.min = Eigen::Vector3d(0, 0, 0);
  a.max = Eigen::Vector3d(4, 4, 3);
  a.has_door = true;
  a.door_min = door_min;
  a.door_max = door_max;
  test::Box b = a;
  b.min = Eigen::Vector3d(4, 0, 0);
  b.max = Eigen::Vector3d(8, 4, 3);
  scene.boxes = {a, b};
  return scene;
}

MapConfig roomConfig() {
  MapConfig c;
  c.voxel_size_m = 0.1;
  c.frontier_min_voxels = 20;
  c.frontier_max_extent_m = 20.0;  // no splitting here: the doorway's frontier is one cluster
  return c;
}

TEST(FrontierMap, EmptyMapHasNoFrontier) {
  OccupancyMap map(roomConfig());
  FrontierMap frontiers(map);
  frontiers.rebuild();
  EXPECT_TRUE(frontiers.clusters(Eigen::Vector3d::Zero()).empty());
}

// With ray_stop_run 4 this test finds 11 more clusters of 22-287 voxels inside room 1: voxels that
// early-stopped rays left unknown. 16 (the default) leaves none, as whole rays (0).
TEST(FrontierMap, OneClusterAtTheDoorwayGoneOnceTheRoomBehindIsSeen) {
  const test::Scene scene = twoRooms();
  OccupancyMap map(roomConfig());
  FrontierMap frontiers(map);
  for (const auto& view : cubeViews(scene, Eigen::Vector3d(2.03, 2.01, 1.02))) frontiers.update(map.integrate(view));
  const auto clusters = frontiers.clusters(Eigen::Vector3d(2, 2, 1));
  ASSERT_EQ(clusters.size(), 1u) << "largest has " << (clusters.empty() ? 0 : clusters[0].num_voxels) << " voxels";
  const FrontierCluster& door = clusters[0];
  // The frontier is the rim of the cone of room 2 seen through the doorway: it starts at the
  // doorway (x = 4) and lies in room 2.
  EXPECT_GE(door.bounds_m.min_m.x(), 3.8);
  EXPECT_LE(door.bounds_m.min_m.x(), 4.3);
  EXPECT_GT(door.centroid_m.x(), 4.0);
  EXPECT_GT(door.num_voxels, 100u);
  EXPECT_NEAR(door.distance_m, (door.centroid_m - Eigen::Vector3d(2, 2, 1)).norm(), 1e-9);

  // Incremental result equals a rebuild.
  FrontierMap fresh(map);
  fresh.rebuild();
  EXPECT_EQ(fresh.numFrontierVoxels(), frontiers.numFrontierVoxels());
  ASSERT_EQ(fresh.clusters(Eigen::Vector3d::Zero()).size(), 1u);
  EXPECT_EQ(fresh.clusters(Eigen::Vector3d::Zero())[0].num_voxels, door.num_voxels);

  // Observe room 2 from its middle: the doorway frontier disappears.
  for (const auto& view : cubeViews(scene, Eigen::Vector3d(6.02, 2.03, 1.01))) frontiers.update(map.integrate(view));
  const auto after = frontiers.clusters(Eigen::Vector3d(2, 2, 1));
  for (const auto& c : after) {
    ADD_FAILURE() << "cluster of " << c.num_voxels << " voxels at (" << c.centroid_m.transpose() << ")";
  }
}

TEST(FrontierMap, LargeClustersAreSplitAndRegionOfInterestLimits) {
  const test::Scene scene = twoRooms();
  MapConfig c = roomConfig();
  c.frontier_max_extent_m = 1.0;
  OccupancyMap map(c);
  FrontierMap frontiers(map);
  Aabb roi;
  roi.min_m = Eigen::Vector3d(0, 0, 0);
  roi.max_m = Eigen::Vector3d(4.5, 4, 3);
  FrontierMap limited(map, roi);
  for (const auto& view : cubeViews(scene, Eigen::Vector3d(2.03, 2.01, 1.02))) {
    const MapDelta delta = map.integrate(view);
    frontiers.update(delta);
    limited.update(delta);
  }
  const auto clusters = frontiers.clusters(Eigen::Vector3d::Zero());
  EXPECT_GT(clusters.size(), 1u);
  for (const auto& cl : clusters) {
    const Eigen::Vector3d extent = cl.bounds_m.max_m - cl.bounds_m.min_m;
    EXPECT_LE(extent.maxCoeff(), 1.0 + 1e-9) << "cluster " << cl.id;
  }
  EXPECT_LT(limited.numFrontierVoxels(), frontiers.numFrontierVoxels());
  // Premise of the loop: the region holds frontiers (an empty list would pass it).
  EXPECT_FALSE(limited.clusters(Eigen::Vector3d::Zero()).empty());
  for (const auto& cl : limited.clusters(Eigen::Vector3d::Zero())) EXPECT_LE(cl.bounds_m.max_m.x(), 4.5 + 1e-9);
}

// The clusters depend only on the map, not on how its changes were grouped into update() calls
// (the server merges changes that arrive while it is busy): one update per view, one update for
// all views, and a rebuild give the same clusters, to the last bit.
TEST(FrontierMap, ClustersDoNotDependOnHowChangesWereGrouped) {
  const test::Scene scene = twoRooms();
  MapConfig config = roomConfig();
  config.frontier_max_extent_m = 0.4;  // many splits: ties on the splitting plane are likely
  config.frontier_min_voxels = 3;
  OccupancyMap map(config);
  FrontierMap per_view(map), merged(map), rebuilt(map);
  MapDelta all;
  for (const Eigen::Vector3d& position : {Eigen::Vector3d(2.03, 2.01, 1.02), Eigen::Vector3d(1.0, 3.0, 1.5)}) {
    for (const auto& view : cubeViews(scene, position)) {
      const MapDelta delta = map.integrate(view);
      per_view.update(delta);
      all.merge(delta);
    }
  }
  merged.update(all);
  rebuilt.rebuild();
  auto key = [](const FrontierMap& f) {
    std::vector<std::tuple<double, double, double, size_t, double, double, double>> out;
    for (const FrontierCluster& c : f.clusters(Eigen::Vector3d::Zero())) {
      out.emplace_back(c.centroid_m.x(), c.centroid_m.y(), c.centroid_m.z(), c.num_voxels, c.direction.x(), c.direction.y(),
                       c.direction.z());
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  const auto expected = key(rebuilt);
  ASSERT_GT(expected.size(), 100u);  // 504 when written
  EXPECT_EQ(key(per_view), expected);
  EXPECT_EQ(key(merged), expected);
}

// The frontier clusters of the whole map the slow way: every free voxel with an unknown face
// neighbour, voxel by voxel; 26-connected components by breadth-first search; each component
// split by the independent reference (tests/mapping/support/reference_cluster_split.h), none of
// FrontierMap's own splitting code.
std::vector<test::ReferenceCluster> bruteForceClusters(const OccupancyMap& map) {
  const auto acc = map.constAccessor();
  std::map<std::tuple<int, int, int>, uint8_t> faces_of;
  for (const BlockIndex& b : acc.knownBlocks()) {
    for (int o = 0; o < kBlockVoxels; ++o) {
      const VoxelIndex v = voxelOfOffset(b, o);
      if (acc.state(v) != VoxelState::kFree) continue;
      uint8_t faces = 0;
      for (int i = 0; i < 6; ++i) {
        if (acc.state(v + test::kReferenceFaceOffsets[i]) == VoxelState::kUnknown) faces |= static_cast<uint8_t>(1 << i);
      }
      if (faces != 0) faces_of[{v.x(), v.y(), v.z()}] = faces;
    }
  }
  std::vector<test::ReferenceCluster> clusters;
  std::map<std::tuple<int, int, int>, bool> visited;
  for (const auto& [start, start_faces] : faces_of) {
    if (visited[start]) continue;
    visited[start] = true;
    std::vector<test::ReferenceVoxel> component;
    std::deque<std::tuple<int, int, int>> open{start};
    while (!open.empty()) {
      const auto [x, y, z] = open.front();
      open.pop_front();
      component.push_back({VoxelIndex(x, y, z), faces_of.at({x, y, z})});
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::tuple<int, int, int> n{x + dx, y + dy, z + dz};
            if (faces_of.count(n) == 0 || visited[n]) continue;
            visited[n] = true;
            open.push_back(n);
          }
    }
    test::referenceSplitComponent(component, map.voxelSize(), map.config().frontier_max_extent_m,
                                  map.config().frontier_min_voxels, clusters);
  }
  return clusters;
}

// FrontierMap's clusters and the reference's are the same sets of voxels: each reference cluster
// pairs with one of FrontierMap's of the same voxel count and bounding box (exactly: both are
// integers times the voxel size) and the same centroid and direction (to 1e-9: FrontierMap sums
// exact integer moments, the reference sums doubles voxel by voxel), none left over on either side.
// A cluster does not list its voxels, so these functions of them stand for the set.
void expectSameClusters(const std::vector<FrontierCluster>& got, const std::vector<test::ReferenceCluster>& expected,
                        const std::string& when) {
  EXPECT_EQ(got.size(), expected.size()) << when;
  std::vector<bool> used(got.size(), false);
  size_t unmatched = 0;
  for (const test::ReferenceCluster& e : expected) {
    bool found = false;
    for (size_t i = 0; i < got.size() && !found; ++i) {
      const FrontierCluster& g = got[i];
      found = !used[i] && g.num_voxels == e.voxels.size() && g.bounds_m.min_m == e.bounds_m.min_m &&
              g.bounds_m.max_m == e.bounds_m.max_m && (g.centroid_m - e.centroid_m).norm() < 1e-9 &&
              (g.direction - e.direction).norm() < 1e-9;
      if (found) used[i] = true;
    }
    if (!found && ++unmatched <= 5) {
      ADD_FAILURE() << when << ": no cluster of FrontierMap is the reference's cluster of " << e.voxels.size()
                    << " voxels, box (" << e.bounds_m.min_m.transpose() << ") - (" << e.bounds_m.max_m.transpose()
                    << "), centroid (" << e.centroid_m.transpose() << ")";
    }
  }
  for (size_t i = 0; i < got.size(); ++i) {
    if (!used[i] && ++unmatched <= 10) {
      ADD_FAILURE() << when << ": FrontierMap's cluster of " << got[i].num_voxels << " voxels, box ("
                    << got[i].bounds_m.min_m.transpose() << ") - (" << got[i].bounds_m.max_m.transpose() << "), centroid ("
                    << got[i].centroid_m.transpose() << ") is none of the reference's";
    }
  }
  EXPECT_EQ(unmatched, 0u) << when;
}

// Incremental updates (views from several places, then a box cleared, which removes frontiers and
// makes new ones) give, after every step, the clusters that a from-scratch, voxel-by-voxel
// computation gives: the block-piece labelling, the re-labelling of only the components that
// changed, and the split by moments of whole runs lose and invent nothing.
TEST(FrontierMap, IncrementalClustersEqualBruteForceAfterEveryStep) {
  const test::Scene scene = twoRooms();
  MapConfig config = roomConfig();
  config.frontier_max_extent_m = 0.6;
  config.frontier_min_voxels = 4;
  OccupancyMap map(config);
  FrontierMap frontiers(map);
  const Eigen::Vector3d positions[3] = {Eigen::Vector3d(2.03, 2.01, 1.02), Eigen::Vector3d(1.0, 3.0, 1.5),
                                        Eigen::Vector3d(6.02, 2.03, 1.01)};
  int step = 0;
  auto check = [&](const char* what) {
    const std::string when = "step " + std::to_string(step++) + " (" + what + ")";
    expectSameClusters(frontiers.clusters(Eigen::Vector3d::Zero()), bruteForceClusters(map), when);
  };
  for (const Eigen::Vector3d& position : positions) {
    const auto views = cubeViews(scene, position);
    for (size_t v = 0; v < views.size(); v += 2) {
      frontiers.update(map.integrate(views[v]));
      if (v + 1 < views.size()) frontiers.update(map.integrate(views[v + 1]));
      check("views");
    }
  }
  Aabb box;
  box.min_m = Eigen::Vector3d(1.0, 1.0, 0.5);
  box.max_m = Eigen::Vector3d(2.5, 2.0, 1.5);
  frontiers.update(map.clearBox(box));
  check("box cleared");
  ASSERT_GT(bruteForceClusters(map).size(), 20u);
}

}  // namespace
}  // namespace cenote::mapping
