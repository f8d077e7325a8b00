// analytic_scene.h: exact depth of analytic scenes (planes, spheres, boxes) seen by a pinhole
// camera, turned into the PointBatch the map integrates. Used by the mapping tests and
// bench/map_bench.cpp. Units: metres, world frame; T_world_cam maps camera to world points, the
// camera looks along its +z axis, x right, y down.
// Threads: plain values and pure functions.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <random>
#include <vector>

#include "common/pinhole_camera.h"
#include "common/point_batch.h"
#include "mapping/integration/depth_frame.h"

namespace cenote::mapping::test {

struct Plane {
  Eigen::Vector3d point;
  Eigen::Vector3d normal;  // unit
};
struct Sphere {
  Eigen::Vector3d centre;
  double radius;
};
// Axis-aligned box; `inside` true makes its walls visible from within (a room), optionally with
// one rectangular opening in a wall (doorway: the axis-aligned rectangle door_min..door_max on the
// wall plane, where no wall is).
struct Box {
  Eigen::Vector3d min;
  Eigen::Vector3d max;
  bool has_door = false;
  Eigen::Vector3d door_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d door_max = Eigen::Vector3d::Zero();
};

struct Scene {
  std::vector<Plane> planes;
  std::vector<Sphere> spheres;
  std::vector<Box> boxes;
  // Distance along a unit ray to the first surface, if any within max_t.
  std::optional<double> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_t) const;
  // Distance from a point to the nearest surface.
  double distanceToSurface(const Eigen::Vector3d& p) const;
};

// The mapping tests' usual camera: 160 x 120 pixels, focal length 120 px, centred.
inline constexpr PinholeCamera kCamera{.width = 160, .height = 120, .fx = 120.0, .fy = 120.0, .cx = 79.5, .cy = 59.5};

// One point per pixel whose ray hits a surface within max_depth_m (others give none: a hole).
// Colours encode the pixel (r = u % 256, g = v % 256, b = 128). noise_m adds Gaussian noise along
// the ray (0: exact).
PointBatch renderBatch(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_world_cam,
                       double max_depth_m, double noise_m = 0.0, uint32_t seed = 1);

// The same view as a depth image (z along the optical axis) with intrinsics and pose, for
// projective integration; pixels that see nothing within max_depth_m have depth NaN. noise_m as
// renderBatch (along the ray), colours as renderBatch.
DepthFrame renderDepth(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_world_cam,
                       double max_depth_m, double noise_m = 0.0, uint32_t seed = 1);

// A spinning multi-beam laser scanner (lidar): `rings` beams at elevations evenly spaced in
// [min_elevation_rad, max_elevation_rad] (from the scanner's x-y plane, +z up), each sampled at
// `columns` azimuths evenly spaced over a full turn, starting at azimuth_offset_rad.
struct LaserScanner {
  int rings = 32;
  int columns = 1024;
  double min_elevation_rad = -0.5;
  double max_elevation_rad = 0.2;
  double azimuth_offset_rad = 0.0;
};

// One point per beam whose ray hits a surface within max_range_m (others give none, as a laser
// without a return), ring by ring. noise_m adds Gaussian noise along the beam (0: exact). No colours.
PointBatch renderScan(const Scene& scene, const LaserScanner& scanner, const Eigen::Isometry3d& T_world_scanner,
                      double max_range_m, double noise_m = 0.0, uint32_t seed = 1);

// A camera at `position` looking at `target` (world up: +z unless looking along it).
Eigen::Isometry3d lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

}  // namespace cenote::mapping::test
