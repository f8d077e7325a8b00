#include "mapping/occupancy_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "common/error.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping {
namespace {

using test::kCamera;
using test::lookAt;
using test::renderBatch;
using test::Scene;

MapConfig smallConfig(double voxel_size_m = 0.05) {
  MapConfig c;
  c.voxel_size_m = voxel_size_m;
  c.num_threads = 2;
  return c;
}

PointBatch oneRay(const Eigen::Vector3d& origin, const Eigen::Vector3f& end) {
  PointBatch b;
  b.origin = origin;
  b.points.push_back(end);
  return b;
}

TEST(MapDelta, MergeKeepsBlocksSortedAndUniqueAndAddsCounts) {
  MapDelta a, b;
  a.changed_blocks = {BlockIndex(-1, 0, 0), BlockIndex(0, 0, 0), BlockIndex(0, 2, 1)};
  a.voxels_updated = 5;
  b.changed_blocks = {BlockIndex(-2, 5, 5), BlockIndex(0, 0, 0), BlockIndex(0, 2, 0), BlockIndex(3, 0, 0)};
  b.voxels_updated = 7;
  a.merge(b);
  const std::vector<BlockIndex> expected = {BlockIndex(-2, 5, 5), BlockIndex(-1, 0, 0), BlockIndex(0, 0, 0),
                                            BlockIndex(0, 2, 0),  BlockIndex(0, 2, 1),  BlockIndex(3, 0, 0)};
  EXPECT_EQ(a.changed_blocks, expected);
  EXPECT_EQ(a.voxels_updated, 12u);
  a.merge(MapDelta{});
  EXPECT_EQ(a.changed_blocks, expected);
}

TEST(OccupancyMap, UnobservedVoxelIsUnknownNotFree) {
  OccupancyMap map(smallConfig());
  auto acc = map.constAccessor();
  EXPECT_EQ(acc.state(VoxelIndex(0, 0, 0)), VoxelState::kUnknown);
  EXPECT_EQ(acc.probability(VoxelIndex(5, -3, 2)), 0.5);
}

TEST(OccupancyMap, CheckBatchWithABoxChecksTheBoxAndNamesABadPointWhenItFails) {
  MapConfig config;
  config.voxel_size_m = 0.05;
  const OccupancyMap map(config);
  PointBatch batch;
  batch.points = {Eigen::Vector3f(1.0f, 2.0f, 3.0f), Eigen::Vector3f(-1.0f, 0.0f, 1.0f)};
  Eigen::AlignedBox3f box;
  for (const Eigen::Vector3f& p : batch.points) box.extend(p);
  EXPECT_NO_THROW(map.checkBatch(batch, box));
  batch.points.push_back(Eigen::Vector3f(1e9f, 0.0f, 0.0f));
  box.extend(batch.points.back());
  try {
    map.checkBatch(batch, box);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("map: point 2 of the batch is"), std::string::npos) << e.what();
  }
  batch.points.clear();
  EXPECT_THROW(map.checkBatch(batch, Eigen::AlignedBox3f()), Error);  // empty: the batch's own message
}

TEST(OccupancyMap, RejectsAbsurdResolution) {
  MapConfig c;
  c.voxel_size_m = 0.0;
  EXPECT_THROW(OccupancyMap{c}, Error);
}

TEST(OccupancyMap, ZeroLengthRayOnlyHits) {
  OccupancyMap map(smallConfig());
  const MapDelta delta = map.integrate(oneRay(Eigen::Vector3d(0.01, 0.01, 0.01), Eigen::Vector3f(0.02f, 0.02f, 0.02f)));
  EXPECT_EQ(delta.voxels_updated, 1u);
  auto acc = map.constAccessor();
  EXPECT_EQ(acc.state(VoxelIndex(0, 0, 0)), VoxelState::kOccupied);
  EXPECT_NEAR(acc.probability(VoxelIndex(0, 0, 0)), 0.7, 1e-6);
}

TEST(OccupancyMap, SingleRayCarvesFreeAndHitsEnd) {
  OccupancyMap map(smallConfig(0.1));
  const MapDelta delta = map.integrate(oneRay(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3f(1.05f, 0.05f, 0.05f)));
  auto acc = map.constAccessor();
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(acc.state(VoxelIndex(i, 0, 0)), VoxelState::kFree) << "voxel (" << i << ",0,0)";
    EXPECT_NEAR(acc.probability(VoxelIndex(i, 0, 0)), 0.4, 1e-6);
  }
  EXPECT_EQ(acc.state(VoxelIndex(10, 0, 0)), VoxelState::kOccupied);
  EXPECT_EQ(acc.state(VoxelIndex(11, 0, 0)), VoxelState::kUnknown);
  EXPECT_EQ(acc.state(VoxelIndex(5, 1, 0)), VoxelState::kUnknown);
  EXPECT_EQ(delta.voxels_updated, 11u);
  ASSERT_EQ(delta.changed_blocks.size(), 2u);
  EXPECT_EQ(delta.changed_voxels.min, VoxelIndex(0, 0, 0));
  EXPECT_EQ(delta.changed_voxels.max, VoxelIndex(10, 0, 0));
}

TEST(OccupancyMap, EachVoxelUpdatedOncePerBatchAndOccupiedWins) {
  OccupancyMap map(smallConfig(0.1));
  PointBatch b;
  b.origin = Eigen::Vector3d(0.05, 0.05, 0.05);
  // Three points in the same end voxel, and one ray ending inside the first ray's path.
  b.points = {Eigen::Vector3f(1.05f, 0.05f, 0.05f), Eigen::Vector3f(1.01f, 0.02f, 0.08f),
              Eigen::Vector3f(1.09f, 0.09f, 0.01f), Eigen::Vector3f(0.55f, 0.05f, 0.05f)};
  map.integrate(b);
  auto acc = map.constAccessor();
  EXPECT_NEAR(acc.probability(VoxelIndex(10, 0, 0)), 0.7, 1e-6);     // one hit, not three
  EXPECT_NEAR(acc.probability(VoxelIndex(2, 0, 0)), 0.4, 1e-6);      // one miss, not two
  EXPECT_EQ(acc.state(VoxelIndex(5, 0, 0)), VoxelState::kOccupied);  // crossed by ray 1, hit by ray 4
  EXPECT_NEAR(acc.probability(VoxelIndex(5, 0, 0)), 0.7, 1e-6);
}

TEST(OccupancyMap, RepeatedHitsClampAtMaximum) {
  OccupancyMap map(smallConfig(0.1));
  for (int i = 0; i < 20; ++i)
    map.integrate(oneRay(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3f(0.55f, 0.05f, 0.05f)));
  auto acc = map.constAccessor();
  EXPECT_NEAR(acc.probability(VoxelIndex(5, 0, 0)), 0.97, 1e-6);
  EXPECT_NEAR(acc.probability(VoxelIndex(2, 0, 0)), 0.12, 1e-6);
}

TEST(OccupancyMap, PointBeyondMaxRangeCarvesToRangeWithoutHit) {
  MapConfig c = smallConfig(0.1);
  c.max_range_m = 1.0;
  OccupancyMap map(c);
  map.integrate(oneRay(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3f(3.05f, 0.05f, 0.05f)));
  auto acc = map.constAccessor();
  for (int i = 0; i < 10; ++i) EXPECT_EQ(acc.state(VoxelIndex(i, 0, 0)), VoxelState::kFree) << "voxel " << i;
  for (int i = 11; i <= 31; ++i) EXPECT_EQ(acc.state(VoxelIndex(i, 0, 0)), VoxelState::kUnknown) << "voxel " << i;
}

TEST(OccupancyMap, BadBatchesAreRejectedAndLeaveMapUnchanged) {
  OccupancyMap map(smallConfig());
  map.integrate(oneRay(Eigen::Vector3d::Zero(), Eigen::Vector3f(1.0f, 0.2f, 0.1f)));
  const MapStats before = map.stats();
  ASSERT_GT(before.occupied, 0u);  // premise: "unchanged" compares a map that holds something
  ASSERT_GT(before.free, 0u);
  const uint64_t version = map.version();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();

  PointBatch empty;
  EXPECT_THROW(map.integrate(empty), Error);
  PointBatch with_nan = oneRay(Eigen::Vector3d::Zero(), Eigen::Vector3f(2.0f, 0.0f, 0.0f));
  with_nan.points.push_back(Eigen::Vector3f(nan, 0.0f, 1.0f));
  EXPECT_THROW(map.integrate(with_nan), Error);
  PointBatch with_inf = oneRay(Eigen::Vector3d::Zero(), Eigen::Vector3f(inf, 0.0f, 0.0f));
  EXPECT_THROW(map.integrate(with_inf), Error);
  PointBatch nan_origin = oneRay(Eigen::Vector3d(std::nan(""), 0.0, 0.0), Eigen::Vector3f(1.0f, 0.0f, 0.0f));
  EXPECT_THROW(map.integrate(nan_origin), Error);
  PointBatch far_point = oneRay(Eigen::Vector3d::Zero(), Eigen::Vector3f(1e9f, 0.0f, 0.0f));
  EXPECT_THROW(map.integrate(far_point), Error);
  PointBatch bad_colors = oneRay(Eigen::Vector3d::Zero(), Eigen::Vector3f(1.0f, 0.0f, 0.0f));
  bad_colors.points.push_back(Eigen::Vector3f(1.0f, 1.0f, 0.0f));
  bad_colors.colors.push_back({1, 2, 3});
  EXPECT_THROW(map.integrate(bad_colors), Error);
  try {
    map.integrate(with_nan);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("point 1 of the batch"), std::string::npos) << e.what();
  }

  const MapStats after = map.stats();
  EXPECT_EQ(after.occupied, before.occupied);
  EXPECT_EQ(after.free, before.free);
  EXPECT_EQ(map.version(), version);
}

// At the edge of the map's range (voxel_types.h, kMaxVoxelIndex) every endpoint keeps its own voxel
// (packed keys there once merged whole rows of them), and a point one voxel beyond is refused.
TEST(OccupancyMap, EndpointsAtTheRangeLimitStayDistinct) {
  OccupancyMap map(smallConfig(1.0));                              // 1 m voxels: float coordinates hold whole voxels there
  const double edge = -static_cast<double>(kMaxVoxelIndex) + 0.5;  // centre of the last voxel
  PointBatch batch;
  batch.origin = Eigen::Vector3d(0.5, edge + 3.0, edge + 3.0);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) batch.points.emplace_back(2.5f, static_cast<float>(edge + i), static_cast<float>(edge + j));
  }
  map.integrate(batch);
  EXPECT_EQ(map.stats().occupied, 16u);
  {
    auto acc = map.constAccessor();
    for (const Eigen::Vector3f& p : batch.points) {
      EXPECT_EQ(acc.state(map.toIndex(p.cast<double>())), VoxelState::kOccupied) << p.transpose();
    }
  }
  EXPECT_THROW(map.integrate(oneRay(batch.origin, Eigen::Vector3f(2.5f, static_cast<float>(edge - 1.0), 0.0f))), Error);
}

// checkBatch's limit is |x| < kMaxVoxelIndex voxels on each axis, whatever the sign (zero, -0.0
// and the last float below the limit pass; the limit itself fails, with the point's message).
TEST(OccupancyMap, PointsUpToTheRangeLimitPassAndTheLimitFails) {
  OccupancyMap map(smallConfig(1.0));
  const float limit = static_cast<float>(kMaxVoxelIndex);  // exact in float
  PointBatch batch;
  batch.origin = Eigen::Vector3d(0.5, -limit + 3.0, 0.5);
  batch.points = {Eigen::Vector3f(-0.0f, std::nextafter(-limit, 0.0f), 0.0f),
                  Eigen::Vector3f(2.5f, std::nextafter(-limit, 0.0f), -0.0f)};
  EXPECT_NO_THROW(map.integrate(batch));
  for (const Eigen::Vector3f& bad : {Eigen::Vector3f(2.5f, -limit, 0.0f), Eigen::Vector3f(2.5f, 0.0f, limit)}) {
    batch.points.push_back(bad);
    try {
      map.integrate(batch);
      ADD_FAILURE() << "accepted " << bad.transpose();
    } catch (const Error& e) {
      std::ostringstream point;
      point << "(" << bad.x() << ", " << bad.y() << ", " << bad.z() << ")";
      EXPECT_EQ(std::string(e.what()), "map: point 2 of the batch is " + point.str() + ": must be finite and within " +
                                           std::to_string(static_cast<double>(kMaxVoxelIndex)) +
                                           " m of 0 (t = " + std::to_string(0.0) + " s)");
    }
    batch.points.pop_back();
  }
}

// Analytic scenes: occupied voxels within one voxel of the surface; free between camera and
// surface; unknown behind it.
// ray_stop_run 0 (whole rays): every sampled voxel between camera and surface is free. The default
// early stop (ray_batch.h) leaves some of them unknown (conservative: never wrongly free), more
// with this sparse 160x120 camera than with a stereo frame: at least 95 % must be free (97.3 %
// with ray_stop_run 4), none occupied.
void checkAnalyticScene(const Scene& scene, const std::vector<Eigen::Isometry3d>& poses, double voxel_size_m,
                        int ray_stop_run = 0) {
  MapConfig config = smallConfig(voxel_size_m);
  config.ray_stop_run = ray_stop_run;
  OccupancyMap map(config);
  PinholeCamera camera = kCamera;
  std::vector<PointBatch> batches;
  for (const auto& T : poses) {
    batches.push_back(renderBatch(scene, camera, T, 8.0));
    map.integrate(batches.back());
  }
  auto acc = map.constAccessor();
  const double s = voxel_size_m;
  size_t occupied = 0;
  for (const BlockIndex& block : acc.knownBlocks()) {
    BlockView view;
    acc.readBlock(block, view);
    for (int o = 0; o < kBlockVoxels; ++o) {
      if (!((view.known[o >> 6] >> (o & 63)) & 1) || !map.model().isOccupied(view.log_odds[o])) continue;
      ++occupied;
      const Eigen::Vector3d c = map.toPoint(voxelOfOffset(block, o));
      // The voxel holds a surface point, so its centre is within half a diagonal of the surface.
      EXPECT_LE(scene.distanceToSurface(c), s * std::sqrt(3.0) / 2 + 1e-9)
          << "occupied voxel at (" << c.transpose() << ") is far from every surface";
    }
  }
  EXPECT_GT(occupied, 100u);
  // Along every 7th ray: free from 2 voxels after the camera to 2 voxels before the surface, and
  // unknown from 2 voxels behind the surface (where no other ray passes) onwards.
  size_t checked_free = 0, found_free = 0, checked_unknown = 0;
  for (const PointBatch& b : batches) {
    for (size_t i = 0; i < b.points.size(); i += 7) {
      // Rays go to the centre of the endpoint voxel (ray_batch.h).
      const Eigen::Vector3d p = map.toPoint(map.toIndex(b.points[i].cast<double>()));
      const Eigen::Vector3d d = (p - b.origin).normalized();
      const double range = (p - b.origin).norm();
      for (double t = 2 * s; t < range - 2 * s; t += s) {
        const Eigen::Vector3d q = b.origin + t * d;
        if (scene.distanceToSurface(q) < 2 * s) continue;  // grazing rays near another surface
        const VoxelState state = acc.state(map.toIndex(q));
        if (ray_stop_run == 0) {
          EXPECT_EQ(state, VoxelState::kFree) << "at (" << q.transpose() << ")";
        }
        EXPECT_NE(state, VoxelState::kOccupied) << "at (" << q.transpose() << ")";
        ++checked_free;
        found_free += state == VoxelState::kFree;
      }
      const Eigen::Vector3d behind = p + 3 * s * d;
      const bool seen_elsewhere = scene.distanceToSurface(behind) < 2 * s;
      if (!seen_elsewhere && poses.size() == 1) {
        EXPECT_EQ(acc.state(map.toIndex(behind)), VoxelState::kUnknown) << "behind (" << behind.transpose() << ")";
        ++checked_unknown;
      }
    }
  }
  EXPECT_GT(checked_free, 1000u);
  EXPECT_GE(found_free, 0.95 * checked_free) << found_free << " of " << checked_free << " free";
  if (poses.size() == 1) {
    EXPECT_GT(checked_unknown, 100u);
  }
}

TEST(OccupancyMap, AnalyticPlaneOccupiedWithinOneVoxelFreeBeforeUnknownBehind) {
  Scene scene;
  scene.planes.push_back({Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)});
  checkAnalyticScene(scene, {lookAt(Eigen::Vector3d(0.013, 0.021, 0.007), Eigen::Vector3d(3, 0.3, -0.2))}, 0.05);
}

TEST(OccupancyMap, AnalyticSphereOccupiedWithinOneVoxelFreeBeforeUnknownBehind) {
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(2.5, 0.1, -0.2), 1.0});
  checkAnalyticScene(scene, {lookAt(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2.5, 0.1, -0.2))}, 0.04);
}

TEST(OccupancyMap, AnalyticSphereWithEarlyStoppingRaysAtLeast95PercentFree) {
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(2.5, 0.1, -0.2), 1.0});
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.0), Eigen::Vector3d(0, 0, 1)});
  checkAnalyticScene(scene, {lookAt(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2.5, 0.1, -0.2))}, 0.04, 16);
}

TEST(OccupancyMap, AnalyticBoxFromTwoPoses) {
  Scene scene;
  test::Box box;
  box.min = Eigen::Vector3d(2.0, -0.5, -0.5);
  box.max = Eigen::Vector3d(3.0, 0.5, 0.5);
  scene.boxes.push_back(box);
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.0), Eigen::Vector3d(0, 0, 1)});
  checkAnalyticScene(scene,
                     {lookAt(Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(2.5, 0, 0)),
                      lookAt(Eigen::Vector3d(0.5, 1.5, 0.8), Eigen::Vector3d(2.5, 0, 0))},
                     0.05);
}

TEST(OccupancyMap, ColourIsMeanOfPointsInVoxel) {
  OccupancyMap map(smallConfig(0.1));
  PointBatch b = oneRay(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3f(1.05f, 0.05f, 0.05f));
  b.points.push_back(Eigen::Vector3f(1.02f, 0.02f, 0.02f));
  b.colors = {{10, 20, 30}, {20, 40, 60}};
  map.integrate(b);
  auto acc = map.constAccessor();
  std::array<uint8_t, 3> rgb{};
  ASSERT_TRUE(acc.color(VoxelIndex(10, 0, 0), rgb));
  EXPECT_EQ(rgb, (std::array<uint8_t, 3>{15, 30, 45}));
  EXPECT_FALSE(acc.color(VoxelIndex(5, 0, 0), rgb));
}

// Endpoints beyond max range record no hit, so no colour: neither in a block their ray carved nor
// in one it never reached; in either integration mode.
TEST(OccupancyMap, ColourOnlyForEndpointsWithinMaxRange) {
  for (int stop_run : {16, 0}) {
    MapConfig c = smallConfig(0.1);
    c.max_range_m = 1.0;
    c.ray_stop_run = stop_run;
    OccupancyMap map(c);
    PointBatch b = oneRay(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3f(0.55f, 0.05f, 0.05f));
    b.points.push_back(Eigen::Vector3f(1.15f, 0.05f, 0.05f));  // voxel 11, block 1 (carved to voxel 9)
    b.points.push_back(Eigen::Vector3f(3.05f, 0.05f, 0.05f));  // voxel 30, block 3 (never reached)
    b.colors = {{10, 20, 30}, {40, 50, 60}, {70, 80, 90}};
    map.integrate(b);
    auto acc = map.constAccessor();
    std::array<uint8_t, 3> rgb{};
    ASSERT_TRUE(acc.color(VoxelIndex(5, 0, 0), rgb)) << "stop_run " << stop_run;
    EXPECT_EQ(rgb, (std::array<uint8_t, 3>{10, 20, 30})) << "stop_run " << stop_run;
    EXPECT_EQ(acc.state(VoxelIndex(9, 0, 0)), VoxelState::kFree) << "stop_run " << stop_run;
    EXPECT_FALSE(acc.color(VoxelIndex(11, 0, 0), rgb)) << "stop_run " << stop_run;
    EXPECT_FALSE(acc.color(VoxelIndex(30, 0, 0), rgb)) << "stop_run " << stop_run;
  }
}

TEST(OccupancyMap, ClearBoxSphereCropAndResetForgetVoxels) {
  OccupancyMap map(smallConfig(0.1));
  Scene scene;
  scene.planes.push_back({Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)});
  map.integrate(renderBatch(scene, kCamera, lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(3, 0, 0)), 8.0));
  const MapStats full = map.stats();
  Aabb box;
  box.min_m = Eigen::Vector3d(0.5, -0.5, -0.5);
  box.max_m = Eigen::Vector3d(1.5, 0.5, 0.5);
  const MapDelta cleared = map.clearBox(box);
  EXPECT_FALSE(cleared.isEmpty());
  {
    auto acc = map.constAccessor();
    EXPECT_EQ(acc.state(map.toIndex(Eigen::Vector3d(1.0, 0.0, 0.0))), VoxelState::kUnknown);
    EXPECT_EQ(acc.state(map.toIndex(Eigen::Vector3d(2.0, 0.0, 0.0))), VoxelState::kFree);
  }
  EXPECT_LT(map.stats().free, full.free);
  map.clearSphere(Eigen::Vector3d(3.0, 0, 0), 0.5);
  {
    auto acc = map.constAccessor();
    EXPECT_EQ(acc.state(map.toIndex(Eigen::Vector3d(3.02, 0.0, 0.0))), VoxelState::kUnknown);
  }
  map.cropToRadius(Eigen::Vector3d::Zero(), 1.0);
  const MapStats cropped = map.stats();
  EXPECT_GT(cropped.free, 0u);
  EXPECT_LE(cropped.bounds_m.max_m.norm(), 1.0 + 0.2);
  map.reset();
  EXPECT_EQ(map.stats().free + map.stats().occupied, 0u);
  EXPECT_THROW(map.clearSphere(Eigen::Vector3d::Zero(), -1.0), Error);
}

TEST(OccupancyMap, BatchedLookupsAnswerAsSingleOnesAlsoAfterClearing) {
  OccupancyMap map(smallConfig(0.1));
  Scene scene;
  scene.planes.push_back({Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)});
  map.integrate(renderBatch(scene, kCamera, lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(3, 0, 0)), 8.0));
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-40, 40);
  std::vector<VoxelIndex> voxels;
  for (int i = 0; i < 20000; ++i) voxels.emplace_back(coord(rng), coord(rng), coord(rng));
  voxels.push_back(VoxelIndex::Constant(std::numeric_limits<int>::max()));  // beyond any map
  voxels.push_back(VoxelIndex(1 << 24, 0, 0));
  for (int round = 0; round < 2; ++round) {
    size_t num_known = 0;
    {
      const auto acc = map.constAccessor();  // released before clearBox below, which waits for readers
      std::vector<float> l(voxels.size(), -99.0f);
      std::vector<uint8_t> known(voxels.size());
      std::vector<VoxelState> states(voxels.size());
      acc.logOdds(voxels, l, known);
      acc.states(voxels, states);
      for (size_t i = 0; i < voxels.size(); ++i) {
        float single = -99.0f;
        const bool single_known = acc.logOdds(voxels[i], single);
        ASSERT_EQ(known[i] != 0, single_known) << "round " << round << ", voxel " << voxels[i].transpose();
        EXPECT_EQ(l[i], single) << "round " << round << ", voxel " << voxels[i].transpose();
        EXPECT_EQ(states[i], acc.state(voxels[i])) << "round " << round << ", voxel " << voxels[i].transpose();
        num_known += single_known;
      }
    }
    EXPECT_GT(num_known, 200u) << "round " << round;  // the random voxels do reach the known ones
    if (round == 0) {
      Aabb box;
      box.min_m = Eigen::Vector3d(0.5, -1.5, -1.5);
      box.max_m = Eigen::Vector3d(1.5, 1.5, 1.5);
      map.clearBox(box);  // deletes leaves: the lookups' leaf index must follow
    }
  }
}

TEST(OccupancyMap, SameMapForAnyThreadCount) {
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(2.5, 0.1, -0.2), 1.0});
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.0), Eigen::Vector3d(0, 0, 1)});
  const PointBatch batch = renderBatch(scene, kCamera, lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(2.5, 0.1, -0.2)),
                                       8.0);
  MapConfig one = smallConfig();
  one.num_threads = 1;
  MapConfig three = smallConfig();
  three.num_threads = 3;
  OccupancyMap a(one), b(three);
  const MapDelta da = a.integrate(batch);
  const MapDelta db = b.integrate(batch);
  EXPECT_EQ(da.changed_blocks, db.changed_blocks);
  EXPECT_EQ(da.voxels_updated, db.voxels_updated);
  auto acc_a = a.constAccessor();
  auto acc_b = b.constAccessor();
  ASSERT_GT(acc_a.knownBlocks().size(), 10u) << "no blocks to compare";
  for (const BlockIndex& block : acc_a.knownBlocks()) {
    BlockView va, vb;
    acc_a.readBlock(block, va);
    acc_b.readBlock(block, vb);
    EXPECT_EQ(va.known, vb.known);
    EXPECT_EQ(va.log_odds, vb.log_odds);
  }
}

}  // namespace
}  // namespace cenote::mapping
