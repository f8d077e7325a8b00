// The same rays into our map and into OctoMap's OcTree::insertPointCloud, voxel by voxel.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <random>

#include "mapping/occupancy_map.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping {
namespace {

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
  const double s = map.voxelSize();
  size_t octomap_known = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    // Pruned leaves stand for 2^k voxels per side.
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / s));
    const octomap::point3d c = it.getCoordinate();
    const VoxelIndex first = map.toIndex(Eigen::Vector3d(c.x() - size / 2 + s / 2, c.y() - size / 2 + s / 2,
                                                         c.z() - size / 2 + s / 2));
    const bool occupied = tree.isNodeOccupied(*it);
    const double p = it->getOccupancy();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          ++octomap_known;
          const VoxelIndex ijk = first + VoxelIndex(i, j, k);
          const VoxelState ours = acc.state(ijk);
          if (ours == VoxelState::kUnknown) {
            ++a.only_octomap;
            continue;
          }
          ++a.both_known;
          if ((ours == VoxelState::kOccupied) == occupied) ++a.same_state;
          if (std::fabs(acc.probability(ijk) - p) < 1e-4) ++a.same_probability;
        }
      }
    }
  }
  const MapStats stats = map.stats();
  a.only_ours = stats.occupied + stats.free - a.both_known;
  return a;
}

octomap::Pointcloud toOctomap(const PointBatch& batch) {
  octomap::Pointcloud cloud;
  cloud.reserve(batch.size());
  for (const auto& p : batch.points) cloud.push_back(p.x(), p.y(), p.z());
  return cloud;
}

// A sea floor with rocks, seen from six poses of a survey, with stereo-like depth noise.
std::vector<PointBatch> surveyFrames(uint32_t seed) {
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -2.0), Eigen::Vector3d(0.05, 0.02, 1.0).normalized()});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-3.0, 3.0), r(0.2, 0.8);
  for (int i = 0; i < 8; ++i) scene.spheres.push_back({Eigen::Vector3d(xy(rng) + 4.0, xy(rng), -2.0), r(rng)});
  test::PinholeCamera camera;
  camera.width = 320;
  camera.height = 240;
  camera.fx = camera.fy = 240.0;
  camera.cx = 159.5;
  camera.cy = 119.5;
  std::vector<PointBatch> frames;
  for (int f = 0; f < 6; ++f) {
    const Eigen::Vector3d position(0.37 * f + 0.013, 0.21 * f - 0.6, 0.3 + 0.05 * f);
    frames.push_back(test::renderBatch(scene, camera, test::lookAt(position, position + Eigen::Vector3d(3.0, 0.3, -1.8)),
                                       12.0, 0.02, seed + f));
  }
  return frames;
}

// The same survey into our map and into OctoMap's insertPointCloud (same origins, endpoints,
// resolution, sensor model and range), then the voxel-by-voxel comparison.
Agreement integrateBothAndCompare(const MapConfig& config, uint32_t seed, bool discretize) {
  OccupancyMap map(config);
  octomap::OcTree tree(config.voxel_size_m);
  configureOctree(tree, config);
  for (const PointBatch& frame : surveyFrames(seed)) {
    map.integrate(frame);
    tree.insertPointCloud(toOctomap(frame), octomap::point3d(frame.origin.x(), frame.origin.y(), frame.origin.z()),
                          config.max_range_m, false, discretize);
  }
  return compare(map, tree);
}

// Discretize on: OctoMap dedups endpoints per voxel and casts each ray to the voxel centre, as we
// do. Differences come only from rounding: OctoMap marches in float (point3d), we in double, so a
// ray passing within ~1e-7 m of a voxel edge may step into a different neighbour; a voxel that one
// map carves and the other does not then differs by one miss. No difference in state is expected
// beyond a handful of voxels, and not a single one on the occupied side of the model.
TEST(OctomapEquivalence, ExactRaysGiveSameStatesAsInsertPointCloudWithDiscretize) {
  MapConfig config;
  config.ray_stop_run = 0;
  config.voxel_size_m = 0.05;
  config.max_range_m = 8.0;
  const Agreement a = integrateBothAndCompare(config, 7, true);
  const double known = static_cast<double>(a.both_known);
  ASSERT_GT(a.both_known, 100000u);
  EXPECT_GE(a.same_state / known, 0.999) << a.same_state << " of " << a.both_known;
  EXPECT_GE(a.same_probability / known, 0.99) << a.same_probability << " of " << a.both_known;
  // Known to one map only: voxels grazed by a ray in one map's rounding and not the other's.
  EXPECT_LE(a.only_octomap + a.only_ours, 0.01 * known) << a.only_octomap << " only OctoMap, " << a.only_ours << " only ours";
  std::cout << "discretize on: " << a.both_known << " voxels known to both, " << a.same_state << " same state, "
            << a.same_probability << " same probability, " << a.only_octomap << " known to OctoMap only, "
            << a.only_ours << " known to ours only\n";
}

// Discretize off: OctoMap casts one ray per point to the point itself, we one per endpoint voxel
// to its centre. The endpoints and the hits are the same; rays to a point instead of its voxel
// centre cross slightly different voxels near the end, so some voxels near surfaces get one more
// miss in OctoMap. The states must still agree on >= 99 % of the voxels known to both.
TEST(OctomapEquivalence, ExactRaysAtLeast99PercentSameStatesAsInsertPointCloudPerPoint) {
  MapConfig config;
  config.ray_stop_run = 0;
  config.voxel_size_m = 0.05;
  config.max_range_m = 8.0;
  const Agreement a = integrateBothAndCompare(config, 11, false);
  const double known = static_cast<double>(a.both_known);
  ASSERT_GT(a.both_known, 100000u);
  EXPECT_GE(a.same_state / known, 0.99) << a.same_state << " of " << a.both_known;
  std::cout << "discretize off: " << a.both_known << " voxels known to both, " << a.same_state << " same state, "
            << a.only_octomap << " known to OctoMap only, " << a.only_ours << " known to ours only\n";
}

// Early-stopping rays with coarse clearing (the default, ray_stop_run 16; integration/ray_batch.h,
// 3. and 5.): each ray stops after 16 voxels (near its end) or 8 cells of 2x2x2 voxels (farther
// than 0.8 m from it) in a row that earlier rays of its chunk already carved, so a voxel that only
// the skipped part of a ray would have carved stays unknown here (0.045 % of the voxels here);
// and farther than 0.8 m from a ray's end all 8 voxels of each cell it crosses are carved, so we
// know about 3 % more voxels than OctoMap (free ones next to rays), and where both maps know a
// voxel it can differ by a miss (same probability 92 %, 99.8 % without coarse clearing). The hits
// are identical. Both must agree on >= 99 % of the voxels known to both (99.99 % here), we may
// know at most 1 % fewer, and at most 5 % more.
TEST(OctomapEquivalence, FastRaysAtLeast99PercentSameStatesAsInsertPointCloudWithDiscretize) {
  MapConfig config;
  config.voxel_size_m = 0.05;
  config.max_range_m = 8.0;
  const Agreement a = integrateBothAndCompare(config, 7, true);
  const double known = static_cast<double>(a.both_known);
  ASSERT_GT(a.both_known, 100000u);
  EXPECT_GE(a.same_state / known, 0.99) << a.same_state << " of " << a.both_known;
  EXPECT_LE(a.only_octomap, 0.01 * known) << a.only_octomap << " known to OctoMap only";
  EXPECT_LE(a.only_ours, 0.05 * known) << a.only_ours << " known to ours only";
  std::cout << "fast rays, discretize on: " << a.both_known << " voxels known to both, " << a.same_state
            << " same state, " << a.same_probability << " same probability, " << a.only_octomap
            << " known to OctoMap only, " << a.only_ours << " known to ours only\n";
}

}  // namespace
}  // namespace cenote::mapping
