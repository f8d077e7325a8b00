// Queries from several threads while one thread integrates, clears and crops: no data race (build with
// -DCENOTE_TSAN=ON to have ThreadSanitizer check it), every answer a valid state, and the final
// map the same as one integrated with nobody reading.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "mapping/distance/distance_field.h"
#include "mapping/frontier/frontier_map.h"
#include "mapping/query/map_query.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping {
namespace {

std::vector<PointBatch> frames() {
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.5), Eigen::Vector3d(0, 0, 1)});
  scene.spheres.push_back({Eigen::Vector3d(3.0, 0.0, -1.0), 0.8});
  std::vector<PointBatch> out;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d p(0.1 * i, 0.05 * i, 0.0);
    out.push_back(test::renderBatch(scene, test::kCamera, test::lookAt(p, Eigen::Vector3d(3, 0, -1)), 8.0));
  }
  return out;
}

TEST(MapConcurrency, QueriesWhileIntegratingSeeValidStatesAndChangeNothing) {
  MapConfig config;
  config.voxel_size_m = 0.05;
  config.publish_blocks = 8;  // many short exclusive sections: readers interleave often
  // libgomp and TBB are not built for ThreadSanitizer: their barriers look like races to it. One
  // ray-marching thread keeps OpenMP out; the map keeps TBB out of stats() and of its destructor.
  config.num_threads = 1;
  OccupancyMap map(config), reference(config);
  FrontierMap frontiers(map);
  DistanceField field(map);
  const auto batches = frames();
  std::atomic<bool> done{false};
  std::atomic<size_t> answers{0}, invalid{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 3; ++t) {
    readers.emplace_back([&, t] {
      std::vector<Eigen::Vector3d> points;
      for (int i = 0; i < 200; ++i) points.emplace_back(0.02 * i, 0.01 * (i % 7) - 0.03 * t, -0.005 * i);
      while (!done.load()) {
        for (const auto& q : queryVoxels(map, points)) {
          invalid += q.state != VoxelState::kUnknown && q.state != VoxelState::kFree && q.state != VoxelState::kOccupied;
        }
        const auto seg = checkSegments(map, {SegmentQuery{Eigen::Vector3d::Zero(), Eigen::Vector3d(3, 0, -1), 0.1}}, false);
        invalid += seg[0].hit && seg[0].hit_distance_m > 3.2;
        field.query(points);
        frontiers.clusters(Eigen::Vector3d::Zero());
        invalid += map.stats().occupied > 10'000'000;
        answers += points.size();
      }
    });
  }
  // Integration, clearing and cropping, as a long mission does them: clears edit the leaf index
  // and the colour store in place while readers look leaves up.
  auto change = [&](auto&& apply) {
    const MapDelta delta = apply(map);
    frontiers.update(delta);
    field.update(delta);
    apply(reference);
  };
  for (size_t i = 0; i < batches.size(); ++i) {
    change([&](OccupancyMap& m) { return m.integrate(batches[i]); });
    const double x = 1.0 + 0.3 * static_cast<double>(i);
    change([&](OccupancyMap& m) {
      return m.clearBox(Aabb{Eigen::Vector3d(x, -0.4, -1.6), Eigen::Vector3d(x + 0.3, 0.4, -1.0)});
    });
    change([&](OccupancyMap& m) { return m.clearSphere(Eigen::Vector3d(3.0, 0.0, -1.0), 0.1 * static_cast<double>(i)); });
  }
  change([&](OccupancyMap& m) { return m.cropToRadius(Eigen::Vector3d::Zero(), 3.0); });
  done = true;
  for (auto& r : readers) r.join();
  EXPECT_GT(answers.load(), 0u);
  EXPECT_EQ(invalid.load(), 0u);
  const MapStats a = map.stats(), b = reference.stats();
  EXPECT_GT(b.occupied, 0u);  // premise: the crop left something to compare
  EXPECT_GT(b.free, 0u);
  EXPECT_EQ(a.occupied, b.occupied);
  EXPECT_EQ(a.free, b.free);
}

}  // namespace
}  // namespace cenote::mapping
