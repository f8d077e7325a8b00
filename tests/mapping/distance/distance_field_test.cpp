#include "mapping/distance/distance_field.h"

#include <gtest/gtest.h>

#include <random>

namespace cenote::mapping {
namespace {

// Occupied voxels of the map, by brute force.
std::vector<VoxelIndex> occupiedVoxels(const OccupancyMap& map) {
  std::vector<VoxelIndex> out;
  const auto acc = map.constAccessor();
  BlockView view;
  for (const BlockIndex& block : acc.knownBlocks()) {
    acc.readBlock(block, view);
    for (int o = 0; o < kBlockVoxels; ++o) {
      if (((view.known[o >> 6] >> (o & 63)) & 1) && map.model().isOccupied(view.log_odds[o])) {
        out.push_back(voxelOfOffset(block, o));
      }
    }
  }
  return out;
}

// Every voxel of the box [-n, n]^3: |field - brute force| <= one voxel, and never below it by more
// than rounding (the field's distance is to some real obstacle). Returns the largest error.
double checkAgainstBruteForce(const OccupancyMap& map, const DistanceField& field, int n) {
  const std::vector<VoxelIndex> occupied = occupiedVoxels(map);
  // Premise: with no obstacle, field and brute force are both max_distance everywhere.
  EXPECT_GT(occupied.size(), 10u) << "no obstacles to measure distances to";
  const double s = map.voxelSize();
  double worst = 0.0;
  size_t exact = 0, total = 0;
  for (int x = -n; x <= n; ++x)
    for (int y = -n; y <= n; ++y)
      for (int z = -n; z <= n; ++z) {
        const VoxelIndex ijk(x, y, z);
        double best2 = std::numeric_limits<double>::infinity();
        for (const VoxelIndex& o : occupied) best2 = std::min(best2, static_cast<double>((o - ijk).squaredNorm()));
        const double truth = std::min(field.maxDistance(), std::sqrt(best2) * s);
        const double ours = field.voxelDistance(ijk);
        EXPECT_LE(ours, truth + s + 1e-9) << "voxel (" << x << "," << y << "," << z << ")";
        EXPECT_GE(ours, truth - 1e-9) << "voxel (" << x << "," << y << "," << z << ")";
        worst = std::max(worst, std::fabs(ours - truth));
        exact += std::fabs(ours - truth) < 1e-9;
        ++total;
      }
  EXPECT_GE(exact, 0.99 * total) << exact << " of " << total << " exact";
  return worst;
}

// Random rays from random origins inside [-1, 1]^3 m: obstacles appear and, hit by later misses,
// disappear again.
PointBatch randomBatch(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-0.95f, 0.95f);
  PointBatch b;
  b.origin = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.5;
  for (int i = 0; i < 60; ++i) b.points.emplace_back(u(rng), u(rng), u(rng));
  return b;
}

MapConfig fieldConfig() {
  MapConfig c;
  c.voxel_size_m = 0.1;
  c.max_distance_m = 0.8;
  c.ray_stop_run = 0;
  return c;
}

TEST(DistanceField, EmptyMapIsMaxDistanceEverywhere) {
  OccupancyMap map(fieldConfig());
  DistanceField field(map);
  field.rebuild();
  const auto q = field.query({Eigen::Vector3d(0.3, 0.2, 0.1)});
  EXPECT_EQ(q[0].distance_m, 0.8);
  EXPECT_FALSE(q[0].within_max);
}

TEST(DistanceField, SingleObstacleDistanceAndGradient) {
  OccupancyMap map(fieldConfig());
  PointBatch b;
  b.origin = Eigen::Vector3d(0.05, 0.05, 0.05);
  b.points = {Eigen::Vector3f(0.55f, 0.05f, 0.05f)};
  DistanceField field(map);
  field.update(map.integrate(b));
  const auto q = field.query(
      {Eigen::Vector3d(0.25, 0.05, 0.05), Eigen::Vector3d(0.55, 0.45, 0.05), Eigen::Vector3d(3, 3, 3)});
  EXPECT_NEAR(q[0].distance_m, 0.3, 1e-9);
  EXPECT_NEAR(q[0].gradient.x(), -1.0, 1e-9);
  EXPECT_NEAR(q[1].distance_m, 0.4, 1e-9);
  EXPECT_NEAR(q[1].gradient.y(), 1.0, 1e-9);
  EXPECT_EQ(q[2].distance_m, 0.8);
}

TEST(DistanceField, WithinOneVoxelOfBruteForceAfterIncrementalUpdatesAndClearing) {
  std::mt19937 rng(17);
  OccupancyMap map(fieldConfig());
  DistanceField field(map);
  for (int i = 0; i < 5; ++i) field.update(map.integrate(randomBatch(rng)));
  EXPECT_LE(checkAgainstBruteForce(map, field, 12), 0.1 + 1e-9);
  // Later batches remove some obstacles (misses) and add others: raise and lower waves.
  for (int i = 0; i < 15; ++i) field.update(map.integrate(randomBatch(rng)));
  EXPECT_LE(checkAgainstBruteForce(map, field, 12), 0.1 + 1e-9);
  Aabb box;
  box.min_m = Eigen::Vector3d(-0.5, -0.5, -0.5);
  box.max_m = Eigen::Vector3d(0.4, 0.3, 0.6);
  field.update(map.clearBox(box));
  EXPECT_LE(checkAgainstBruteForce(map, field, 12), 0.1 + 1e-9);
  // The incremental field equals one rebuilt from scratch within a voxel as well.
  DistanceField fresh(map);
  fresh.rebuild();
  EXPECT_LE(checkAgainstBruteForce(map, fresh, 12), 0.1 + 1e-9);
}

}  // namespace
}  // namespace cenote::mapping
