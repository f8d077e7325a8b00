// OccupancyMap::integrateDepth (integration/projective_batch.h): analytic scenes seen as depth
// images, against the geometry and against ray integration of the same view.
#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"
#include "mapping/integration/depth_frame.h"
#include "mapping/occupancy_map.h"
#include "tests/mapping/support/analytic_scene.h"
#include "tests/mapping/support/map_configs.h"

namespace cenote::mapping {
namespace {

// A floor 1.52 m below a camera looking 30 degrees down (between voxel faces: a floor exactly on a
// face would put each point in the voxel above or below it by rounding), with a sphere on it.
test::Scene floorScene() {
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.52), Eigen::Vector3d::UnitZ()});
  scene.spheres.push_back({Eigen::Vector3d(3.0, 0.3, -1.2), 0.5});
  return scene;
}

Eigen::Isometry3d floorPose() {
  return test::lookAt(Eigen::Vector3d(0.01, 0.02, 0.03), Eigen::Vector3d(std::cos(0.52), 0.0, -std::sin(0.52)));
}

MapConfig config() { return test::mapConfig(0.05, 8.0); }

// Sampled pixels away from the image border (a voxel there may have its centre outside the image):
// every surface point's voxel is occupied; points on its ray more than two voxels before it are
// free, except near silhouettes, where a voxel's centre can fall into a pixel that sees the nearer
// object (at most 1 % of the samples); the floor three voxels below a surface point is unknown.
TEST(ProjectiveIntegration, OccupiedOnTheSurfaceFreeBeforeItUnknownBehind) {
  const test::Scene scene = floorScene();
  const PinholeCamera camera = test::kCamera;
  const DepthFrame frame = test::renderDepth(scene, camera, floorPose(), 12.0);
  OccupancyMap map(config());
  const MapDelta delta = map.integrateDepth(frame);
  ASSERT_FALSE(delta.isEmpty());
  const auto acc = map.constAccessor();
  const double s = map.voxelSize();
  const Eigen::Vector3d origin = frame.T_world_cam.translation();
  size_t surfaces = 0, free_samples = 0, free_ok = 0, below = 0;
  for (int v = 4; v < camera.height - 4; v += 7) {
    for (int u = 4; u < camera.width - 4; u += 9) {
      const float z = frame.depth_m[static_cast<size_t>(v) * camera.width + u];
      if (!std::isfinite(z)) continue;
      const Eigen::Vector3d p_cam(z * (u - camera.cx) / camera.fx, z * (v - camera.cy) / camera.fy, z);
      const Eigen::Vector3d surface = frame.T_world_cam * p_cam;
      if ((surface - origin).norm() > 7.5) continue;
      ++surfaces;
      EXPECT_EQ(acc.state(map.toIndex(surface)), VoxelState::kOccupied) << "pixel (" << u << "," << v << ")";
      const Eigen::Vector3d dir = (surface - origin).normalized();
      const double range = (surface - origin).norm();
      for (double t = 0.3; t < range - 2.5 * s; t += 0.37) {
        ++free_samples;
        free_ok += acc.state(map.toIndex(origin + t * dir)) == VoxelState::kFree;
      }
      if (std::fabs(surface.z() + 1.52) < 1e-3) {  // on the floor
        ++below;
        EXPECT_EQ(acc.state(map.toIndex(surface - Eigen::Vector3d(0, 0, 3.5 * s))), VoxelState::kUnknown)
            << "below pixel (" << u << "," << v << ")";
      }
    }
  }
  EXPECT_GT(surfaces, 100u);
  EXPECT_GT(below, 50u);
  EXPECT_GE(free_ok, 0.99 * free_samples) << free_ok << " of " << free_samples << " samples before the surface free";
}

TEST(ProjectiveIntegration, PixelsWithoutDepthCarveNothing) {
  const PinholeCamera camera = test::kCamera;
  DepthFrame frame = test::renderDepth(floorScene(), camera, floorPose(), 12.0);
  // A hole in the middle of the image (a stereo hole): the space in front of it stays unknown.
  for (int v = 40; v < 80; ++v) {
    for (int u = 60; u < 100; ++u) frame.depth_m[static_cast<size_t>(v) * camera.width + u] = 0.0f;
  }
  OccupancyMap map(config());
  map.integrateDepth(frame);
  const auto acc = map.constAccessor();
  const Eigen::Vector3d centre_ray = frame.T_world_cam.linear() *
                                     Eigen::Vector3d((80 - camera.cx) / camera.fx, (60 - camera.cy) / camera.fy, 1.0);
  for (double t = 0.8; t < 3.0; t += 0.2) {
    const Eigen::Vector3d p = frame.T_world_cam.translation() + t * centre_ray.normalized();
    EXPECT_EQ(acc.state(map.toIndex(p)), VoxelState::kUnknown) << "at " << t << " m along the hole's centre ray";
  }
  // Positive control: without the hole the same samples are carved free, so "unknown" above is the
  // hole's doing and not a ray that would never have reached them.
  OccupancyMap full(config());
  full.integrateDepth(test::renderDepth(floorScene(), camera, floorPose(), 12.0));
  const auto full_acc = full.constAccessor();
  int carved = 0, samples = 0;
  for (double t = 0.8; t < 3.0; t += 0.2, ++samples) {
    const Eigen::Vector3d p = frame.T_world_cam.translation() + t * centre_ray.normalized();
    carved += full_acc.state(full.toIndex(p)) == VoxelState::kFree;
  }
  EXPECT_EQ(carved, samples) << "without the hole, " << carved << " of " << samples << " samples are free";
}

// The same view by rays (ray_stop_run 0, every ray whole) and by projection. The hits are the same
// voxels (the back-projected points); free space differs where a voxel is crossed by some ray but
// its centre's pixel sees no farther (near silhouettes and grazing the floor), and in the voxel
// just before each surface, which projection leaves alone.
TEST(ProjectiveIntegration, AgreesWithRayIntegrationOfTheSameView) {
  const test::Scene scene = floorScene();
  const PinholeCamera camera = test::kCamera;
  MapConfig c = config();
  c.ray_stop_run = 0;
  OccupancyMap rays(c), projected(c);
  rays.integrate(test::renderBatch(scene, camera, floorPose(), 12.0));
  projected.integrateDepth(test::renderDepth(scene, camera, floorPose(), 12.0));
  const auto a = rays.constAccessor();
  const auto b = projected.constAccessor();
  size_t both = 0, same = 0, rays_only = 0, projected_only = 0, occupied_same = 0, occupied_rays = 0;
  for (const BlockIndex& block : a.knownBlocks()) {
    for (int o = 0; o < kBlockVoxels; ++o) {
      const VoxelIndex ijk = voxelOfOffset(block, o);
      const VoxelState sa = a.state(ijk);
      if (sa == VoxelState::kUnknown) continue;
      const VoxelState sb = b.state(ijk);
      if (sa == VoxelState::kOccupied) {
        ++occupied_rays;
        occupied_same += sb == VoxelState::kOccupied;
      }
      if (sb == VoxelState::kUnknown) {
        ++rays_only;
        continue;
      }
      ++both;
      same += sa == sb;
    }
  }
  projected_only = projected.stats().free + projected.stats().occupied - both;
  std::cout << both << " voxels known to both, " << same << " same state; " << rays_only << " known to rays only, "
            << projected_only << " to projection only; " << occupied_same << " of " << occupied_rays
            << " occupied voxels the same\n";
  ASSERT_GT(both, 10000u);
  EXPECT_GE(static_cast<double>(same) / both, 0.99);
  EXPECT_GE(static_cast<double>(occupied_same) / occupied_rays, 0.98);
  EXPECT_LE(static_cast<double>(rays_only + projected_only) / both, 0.15);
}

TEST(ProjectiveIntegration, SameMapForAnyThreadCount) {
  const DepthFrame frame = test::renderDepth(floorScene(), test::kCamera, floorPose(), 12.0, 0.01);
  MapConfig c = config();
  c.num_threads = 1;
  OccupancyMap one(c);
  c.num_threads = 3;
  OccupancyMap three(c);
  const MapDelta da = one.integrateDepth(frame), db = three.integrateDepth(frame);
  EXPECT_EQ(da.changed_blocks, db.changed_blocks);
  EXPECT_EQ(da.voxels_updated, db.voxels_updated);
  ASSERT_GT(one.stats().occupied, 0u);  // premise: two empty maps would be equal too
  ASSERT_GT(one.stats().free, 0u);
  EXPECT_EQ(one.stats().free, three.stats().free);
  EXPECT_EQ(one.stats().occupied, three.stats().occupied);
}

TEST(ProjectiveIntegration, BadFramesAreRejectedAndLeaveTheMapUnchanged) {
  OccupancyMap map(config());
  const DepthFrame good = test::renderDepth(floorScene(), test::kCamera, floorPose(), 12.0);
  DepthFrame short_depth = good;
  short_depth.depth_m.pop_back();
  DepthFrame bad_focal = good;
  bad_focal.fx = 0.0;
  DepthFrame bad_pose = good;
  bad_pose.T_world_cam.translation().x() = std::nan("");
  DepthFrame bad_colors = good;
  bad_colors.colors.resize(5);
  DepthFrame empty = good;
  empty.width = 0;
  for (const DepthFrame* f : {&short_depth, &bad_focal, &bad_pose, &bad_colors, &empty}) {
    EXPECT_THROW(map.integrateDepth(*f), Error);
  }
  try {
    map.integrateDepth(short_depth);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depths for"), std::string::npos) << e.what();
  }
  EXPECT_EQ(map.version(), 0u);
  EXPECT_EQ(map.stats().free + map.stats().occupied, 0u);
  // Positive control: the frame they were made from does change the map.
  map.integrateDepth(good);
  EXPECT_GT(map.version(), 0u);
  EXPECT_GT(map.stats().occupied, 0u);
}

}  // namespace
}  // namespace cenote::mapping
