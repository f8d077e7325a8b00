// The same rays into our map and into OctoMap's OcTree::insertPointCloud, voxel by voxel.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <random>
#include <vector>

#include "mapping/occupancy_map.h"
#include "tests/mapping/support/analytic_scene.h"
#include "tests/mapping/support/map_configs.h"
#include "tests/mapping/support/voxel_sets.h"

namespace cenote::mapping {
namespace {

using test::countNotIn;
using test::forEachLeafVoxel;
using test::insertPointCloud;
using test::VoxelSets;
using test::voxelSets;

struct Agreement {
  size_t both_known = 0;
  size_t same_state = 0;
  size_t same_probability = 0;  // |p_ours - p_octomap| < 1e-4
  size_t only_octomap = 0;
  size_t only_ours = 0;
};

void configureOctree(octomap::OcTree& tree, const MapConfig& c) {
  tree.setProbHit(c.prob_hit);
  tree.setProbMiss(c.prob_miss);
  tree.setClampingThresMin(c.clamp_min);
  tree.setClampingThresMax(c.clamp_max);
  tree.setOccupancyThres(c.occupied_threshold);
}

Agreement compare(const OccupancyMap& map, const octomap::OcTree& tree) {
  Agreement a;
  auto acc = map.constAccessor();
  forEachLeafVoxel(tree, map, [&](const VoxelIndex& ijk, const auto& leaf) {
    const VoxelState ours = acc.state(ijk);
    if (ours == VoxelState::kUnknown) {
      ++a.only_octomap;
      return;
    }
    ++a.both_known;
    if ((ours == VoxelState::kOccupied) == tree.isNodeOccupied(*leaf)) ++a.same_state;
    if (std::fabs(acc.probability(ijk) - leaf->getOccupancy()) < 1e-4) ++a.same_probability;
  });
  const MapStats stats = map.stats();
  a.only_ours = stats.occupied + stats.free - a.both_known;
  return a;
}

// A sea floor with rocks, seen from six poses of a survey, with stereo-like depth noise.
std::vector<PointBatch> surveyFrames(uint32_t seed) {
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -2.0), Eigen::Vector3d(0.05, 0.02, 1.0).normalized()});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-3.0, 3.0), r(0.2, 0.8);
  for (int i = 0; i < 8; ++i) scene.spheres.push_back({Eigen::Vector3d(xy(rng) + 4.0, xy(rng), -2.0), r(rng)});
  const PinholeCamera camera{.width = 320, .height = 240, .fx = 240.0, .fy = 240.0, .cx = 159.5, .cy = 119.5};
  std::vector<PointBatch> frames;
  for (int f = 0; f < 6; ++f) {
    const Eigen::Vector3d position(0.37 * f + 0.013, 0.21 * f - 0.6, 0.3 + 0.05 * f);
    frames.push_back(test::renderBatch(scene, camera, test::lookAt(position, position + Eigen::Vector3d(3.0, 0.3, -1.8)),
                                       12.0, 0.02, seed + f));
  }
  return frames;
}

// Whole rays (ray_stop_run 0) at 5 cm up to 8 m: the survey's settings.
MapConfig exactRays() {
  MapConfig config = test::mapConfig(0.05, 8.0);
  config.ray_stop_run = 0;
  return config;
}

// The same survey into our map and into OctoMap's insertPointCloud (same origins, endpoints,
// resolution, sensor model and range), then the voxel-by-voxel comparison.
Agreement integrateBothAndCompare(const MapConfig& config, uint32_t seed, bool discretize) {
  OccupancyMap map(config);
  octomap::OcTree tree(config.voxel_size_m);
  configureOctree(tree, config);
  for (const PointBatch& frame : surveyFrames(seed)) {
    map.integrate(frame);
    insertPointCloud(tree, frame, config.max_range_m, discretize);
  }
  return compare(map, tree);
}

// Discretize on: OctoMap dedups endpoints per voxel and casts each ray to the voxel centre, as we
// do. Differences come only from rounding: OctoMap marches in float (point3d), we in double, so a
// ray passing within ~1e-7 m of a voxel edge may step into a different neighbour; a voxel that one
// map carves and the other does not then differs by one miss. No difference in state is expected
// beyond a handful of voxels, and not a single one on the occupied side of the model.
TEST(OctomapEquivalence, ExactRaysGiveSameStatesAsInsertPointCloudWithDiscretize) {
  const Agreement a = integrateBothAndCompare(exactRays(), 7, true);
  const double known = static_cast<double>(a.both_known);
  ASSERT_GT(a.both_known, 100000u);
  EXPECT_GE(a.same_state / known, 0.999) << a.same_state << " of " << a.both_known;
  EXPECT_GE(a.same_probability / known, 0.99) << a.same_probability << " of " << a.both_known;
  // Known to one map only: voxels grazed by a ray in one map's rounding and not the other's.
  EXPECT_LE(a.only_octomap + a.only_ours, 0.01 * known)
      << a.only_octomap << " only OctoMap, " << a.only_ours << " only ours";
  std::cout << "discretize on: " << a.both_known << " voxels known to both, " << a.same_state << " same state, "
            << a.same_probability << " same probability, " << a.only_octomap << " known to OctoMap only, " << a.only_ours
            << " known to ours only\n";
}

// Discretize off: OctoMap casts one ray per point to the point itself, we one per endpoint voxel
// to its centre. The endpoints and the hits are the same; rays to a point instead of its voxel
// centre cross slightly different voxels near the end, so some voxels near surfaces get one more
// miss in OctoMap. The states must still agree on >= 99 % of the voxels known to both.
TEST(OctomapEquivalence, ExactRaysAtLeast99PercentSameStatesAsInsertPointCloudPerPoint) {
  const Agreement a = integrateBothAndCompare(exactRays(), 11, false);
  const double known = static_cast<double>(a.both_known);
  ASSERT_GT(a.both_known, 100000u);
  EXPECT_GE(a.same_state / known, 0.99) << a.same_state << " of " << a.both_known;
  std::cout << "discretize off: " << a.both_known << " voxels known to both, " << a.same_state << " same state, "
            << a.only_octomap << " known to OctoMap only, " << a.only_ours << " known to ours only\n";
}

// Early-stopping rays (the default, ray_stop_run 32; integration/ray_batch.h, 3.): each ray,
// marched from its end, stops after 32 voxels in a row that earlier rays of its chunk already
// carved, so a voxel that only the skipped part of a ray would have carved stays unknown here (209
// voxels, 0.032 %; 266 with a run of 16 in image order, until issue 19's passes), and where
// both maps know a voxel it can differ by a miss (same probability 99.9 %). Every voxel carved lies
// on its ray's whole walk, so we know no voxel OctoMap does not, but for whole rays' rounding (the
// test above: 10 here). The hits are identical. Both must agree on >= 99.9 % of the voxels known to
// both (99.9998 % here), we may know at most 1 % fewer, and at most 0.01 % more. (With coarse
// clearing, until issue 14: 3 % more, 92 % same probability.)
TEST(OctomapEquivalence, FastRaysAtLeast99PercentSameStatesAsInsertPointCloudWithDiscretize) {
  MapConfig config;
  config.voxel_size_m = 0.05;
  config.max_range_m = 8.0;
  const Agreement a = integrateBothAndCompare(config, 7, true);
  const double known = static_cast<double>(a.both_known);
  ASSERT_GT(a.both_known, 100000u);
  EXPECT_GE(a.same_state / known, 0.999) << a.same_state << " of " << a.both_known;
  EXPECT_LE(a.only_octomap, 0.01 * known) << a.only_octomap << " known to OctoMap only";
  EXPECT_LE(a.only_ours, 1e-4 * known) << a.only_ours << " known to ours only";
  std::cout << "fast rays, discretize on: " << a.both_known << " voxels known to both, " << a.same_state << " same state, "
            << a.same_probability << " same probability, " << a.only_octomap << " known to OctoMap only, " << a.only_ours
            << " known to ours only\n";
}

// A spinning 32-beam laser scanner 1.7 m above the ground in a yard: a ground plane, walls 4-6 m
// high on three sides (open on the fourth, and over the walls: beams with no return), a building,
// a parked van and trees; returns from 2 m to 45 m, 2 cm range noise. The map's maximum range
// (25 m) is shorter than the farthest returns: those rays carve to 25 m and record no hit.
PointBatch laserScan() {
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.01, -0.02, 1.0).normalized()});
  auto box = [](Eigen::Vector3d min, Eigen::Vector3d max) {
    test::Box b;
    b.min = min;
    b.max = max;
    return b;
  };
  scene.boxes.push_back(box({-40.0, 18.0, -1.0}, {40.0, 18.4, 5.0}));    // wall, north
  scene.boxes.push_back(box({-40.0, -22.4, -1.0}, {40.0, -22.0, 4.0}));  // wall, south
  scene.boxes.push_back(box({-25.4, -22.0, -1.0}, {-25.0, 18.0, 6.0}));  // wall, west (east is open)
  scene.boxes.push_back(box({6.0, 4.0, -1.0}, {14.0, 11.0, 7.5}));       // building
  scene.boxes.push_back(box({-5.2, -6.0, -1.0}, {-3.3, -1.2, 2.1}));     // van
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> x(-22.0, 35.0), y(-20.0, 16.0), r(0.4, 1.6);
  for (int i = 0; i < 24; ++i) {
    const Eigen::Vector3d centre(x(rng), y(rng), 0.0);
    if (centre.head<2>().norm() < 4.0) continue;  // nothing on the scanner
    const double radius = r(rng);
    scene.spheres.push_back({centre + Eigen::Vector3d(0, 0, 2.0 + radius), radius});  // crown
    scene.spheres.push_back({centre + Eigen::Vector3d(0, 0, 0.6), 0.25});             // trunk
  }
  test::LaserScanner scanner;
  scanner.rings = 32;
  scanner.columns = 1024;
  scanner.min_elevation_rad = -0.43;  // -25 degrees
  scanner.max_elevation_rad = 0.26;   // +15 degrees
  scanner.azimuth_offset_rad = 0.0123;
  Eigen::Isometry3d T_world_scanner = Eigen::Isometry3d::Identity();
  T_world_scanner.linear() = Eigen::AngleAxisd(0.31, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_world_scanner.translation() = Eigen::Vector3d(0.437, -0.213, 1.731);
  return test::renderScan(scene, scanner, T_world_scanner, 45.0, 0.02, 5);
}

// One laser scan at 0.1 m into our map and into OctoMap's insertPointCloud (discretize on: one ray
// per endpoint voxel to its centre, as ours), the same origin, sensor model and range.
struct ScanComparison {
  VoxelSets ours, octomap;
};
ScanComparison integrateScanIntoBoth(const MapConfig& config) {
  const PointBatch scan = laserScan();
  OccupancyMap map(config);
  map.integrate(scan);
  octomap::OcTree tree(config.voxel_size_m);
  configureOctree(tree, config);
  insertPointCloud(tree, scan, config.max_range_m, true);
  return {voxelSets(map), voxelSets(tree, map)};
}

MapConfig laserConfig() { return test::mapConfig(0.1, 25.0); }

// Whole rays (ray_stop_run 0) against OctoMap on the laser scan: the same hits, and the same free
// voxels up to rounding. OctoMap casts from float coordinates (its point3d origin and voxel centres,
// ~1e-7 m off ours) and steps in float directions, so a ray passing within that of a voxel edge or
// corner crosses the neighbour on the other side of it in one map: 37 voxels each way of 1.43M
// here (3e-5); at most 1e-4 allowed.
TEST(OctomapEquivalence, ExactRaysOnALaserScanGiveInsertPointCloudsVoxelSetsUpToRounding) {
  MapConfig config = laserConfig();
  config.ray_stop_run = 0;
  const ScanComparison c = integrateScanIntoBoth(config);
  ASSERT_GT(c.octomap.free.size(), 1000000u);
  const size_t extra_free = countNotIn(c.ours.free, c.octomap.free);
  const size_t missing_free = countNotIn(c.octomap.free, c.ours.free);
  EXPECT_LE(extra_free, 1e-4 * c.octomap.free.size()) << "free here but not in OctoMap";
  EXPECT_LE(missing_free, 1e-4 * c.octomap.free.size()) << "free in OctoMap but not here";
  EXPECT_EQ(c.ours.occupied, c.octomap.occupied)
      << c.ours.occupied.size() << " occupied here, " << c.octomap.occupied.size() << " in OctoMap";
  std::cout << "laser scan, whole rays: " << c.ours.free.size() << " free (OctoMap " << c.octomap.free.size() << "), "
            << extra_free << " free only here, " << missing_free << " free only in OctoMap\n";
}

// A planner takes a free voxel as safe to fly through, so a voxel that no exact ray crosses must not
// be free. The default (rays marched from their end, stopped after ray_stop_run voxels in a row
// already carved) may leave voxels of a ray unknown, but every voxel it makes free lies on that ray's
// whole walk: its free set is a subset of ray_stop_run 0's, exactly, and so it holds no voxel free
// that OctoMap does not, except where rounding already separates whole rays from OctoMap (the test
// above): 0 beyond those. The hits (the same endpoint voxels) are the same set. Until issue 14 the
// default also carved 2x2x2-voxel cells along the far part of each ray: 2470836 free voxels here,
// 1051985 of them (74 % of OctoMap's 1426995) free in no exact ray.
TEST(OctomapEquivalence, DefaultRaysOnALaserScanMakeFreeOnlyVoxelsInsertPointCloudMakesFree) {
  const MapConfig config = laserConfig();
  ASSERT_GT(config.ray_stop_run, 0) << "the default is meant to stop rays early";
  MapConfig whole_config = config;
  whole_config.ray_stop_run = 0;
  const ScanComparison c = integrateScanIntoBoth(config);
  const ScanComparison whole = integrateScanIntoBoth(whole_config);
  ASSERT_GT(c.octomap.free.size(), 1000000u);
  ASSERT_GT(c.octomap.occupied.size(), 10000u);
  EXPECT_EQ(countNotIn(c.ours.free, whole.ours.free), 0u) << "free with early stopping but not with whole rays";
  std::vector<uint64_t> extra, whole_extra;
  std::set_difference(c.ours.free.begin(), c.ours.free.end(), c.octomap.free.begin(), c.octomap.free.end(),
                      std::back_inserter(extra));
  std::set_difference(whole.ours.free.begin(), whole.ours.free.end(), c.octomap.free.begin(), c.octomap.free.end(),
                      std::back_inserter(whole_extra));
  EXPECT_EQ(countNotIn(extra, whole_extra), 0u)
      << "free here but not in OctoMap, beyond the " << whole_extra.size() << " voxels of whole rays' rounding";
  EXPECT_LE(extra.size(), 1e-4 * c.octomap.free.size());
  EXPECT_EQ(c.ours.occupied, c.octomap.occupied)
      << c.ours.occupied.size() << " occupied here, " << c.octomap.occupied.size() << " in OctoMap";
  // Left unknown by early stopping: 1507 voxels here (0.11 %; 3566 with a run of 16 in image order).
  const size_t missing_free = countNotIn(c.octomap.free, c.ours.free);
  EXPECT_LE(missing_free, 0.01 * c.octomap.free.size()) << "free in OctoMap, unknown here";
  std::cout << "laser scan, default rays: " << c.ours.free.size() << " free (OctoMap " << c.octomap.free.size() << "), "
            << extra.size() << " free only here (whole rays: " << whole_extra.size() << "), " << missing_free
            << " free only in OctoMap; " << c.ours.occupied.size() << " occupied (OctoMap " << c.octomap.occupied.size()
            << ")\n";
}

}  // namespace
}  // namespace cenote::mapping
