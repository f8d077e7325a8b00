#include "tests/mapping/support/analytic_scene.h"

#include <array>
#include <cmath>
#include <limits>

namespace cenote::mapping::test {
namespace {

std::optional<double> hitPlane(const Plane& plane, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const double denom = plane.normal.dot(d);
  if (std::fabs(denom) < 1e-12) return std::nullopt;
  const double t = plane.normal.dot(plane.point - o) / denom;
  if (t <= 0.0) return std::nullopt;
  return t;
}

std::optional<double> hitSphere(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d oc = o - s.centre;
  const double b = oc.dot(d);
  const double c = oc.squaredNorm() - s.radius * s.radius;
  const double disc = b * b - c;
  if (disc < 0.0) return std::nullopt;
  const double sq = std::sqrt(disc);
  if (-b - sq > 0.0) return -b - sq;
  if (-b + sq > 0.0) return -b + sq;
  return std::nullopt;
}

bool inDoor(const Box& box, const Eigen::Vector3d& p) {
  if (!box.has_door) return false;
  const double eps = 1e-9;
  return (p.array() >= box.door_min.array() - eps).all() && (p.array() <= box.door_max.array() + eps).all();
}

// Nearest crossing of any of the six wall planes that lies on the wall (and not in the door).
std::optional<double> hitBox(const Box& box, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  std::optional<double> best;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::fabs(d[axis]) < 1e-12) continue;
    for (double wall : {box.min[axis], box.max[axis]}) {
      const double t = (wall - o[axis]) / d[axis];
      if (t <= 1e-9) continue;
      const Eigen::Vector3d p = o + t * d;
      bool on = true;
      for (int k = 0; k < 3; ++k) {
        if (k != axis && (p[k] < box.min[k] || p[k] > box.max[k])) on = false;
      }
      if (!on || inDoor(box, p)) continue;
      if (!best || t < *best) best = t;
    }
  }
  return best;
}

}  // namespace

std::optional<double> Scene::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t) const {
  std::optional<double> best;
  auto take = [&](std::optional<double> t) {
    if (t && *t <= max_t && (!best || *t < *best)) best = t;
  };
  for (const auto& p : planes) take(hitPlane(p, o, d));
  for (const auto& s : spheres) take(hitSphere(s, o, d));
  for (const auto& b : boxes) take(hitBox(b, o, d));
  return best;
}

double Scene::distanceToSurface(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& plane : planes) best = std::min(best, std::fabs(plane.normal.dot(p - plane.point)));
  for (const auto& s : spheres) best = std::min(best, std::fabs((p - s.centre).norm() - s.radius));
  for (const auto& b : boxes) {
    // Distance to the box surface (walls), ignoring doors (tests keep away from them).
    const Eigen::Vector3d q = p.cwiseMax(b.min).cwiseMin(b.max);
    if ((q - p).squaredNorm() > 0.0) {
      best = std::min(best, (q - p).norm());
    } else {
      const Eigen::Vector3d a = p - b.min;
      const Eigen::Vector3d c = b.max - p;
      best = std::min(best, std::min(a.minCoeff(), c.minCoeff()));
    }
  }
  return best;
}

namespace {

// Casts the ray of every pixel, row by row, from the camera's centre into the scene, and calls
// hit(u, v, d_cam, d_world, range_m) for each that meets a surface within max_depth_m: d_cam the
// pixel's ray at z = 1, d_world its unit direction, range_m the distance with Gaussian noise of
// sigma noise_m (drawn from `seed` in pixel order, hits only).
template <typename Hit>
void castPixelRays(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_world_cam,
                   double max_depth_m, double noise_m, uint32_t seed, Hit&& hit) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m > 0.0 ? noise_m : 1.0);
  const Eigen::Vector3d origin = T_world_cam.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d d_cam((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      const Eigen::Vector3d d = (T_world_cam.linear() * d_cam).normalized();
      const auto t = scene.intersect(origin, d, max_depth_m);
      if (!t) continue;
      hit(u, v, d_cam, d, *t + (noise_m > 0.0 ? noise(rng) : 0.0));
    }
  }
}

std::array<uint8_t, 3> pixelColor(int u, int v) {
  return {static_cast<uint8_t>(u % 256), static_cast<uint8_t>(v % 256), 128};
}

}  // namespace

PointBatch renderBatch(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_world_cam,
                       double max_depth_m, double noise_m, uint32_t seed) {
  PointBatch batch;
  batch.origin = T_world_cam.translation();
  batch.points.reserve(static_cast<size_t>(camera.width) * camera.height);
  castPixelRays(scene, camera, T_world_cam, max_depth_m, noise_m, seed,
                [&](int u, int v, const Eigen::Vector3d&, const Eigen::Vector3d& d, double range_m) {
                  batch.points.push_back((batch.origin + range_m * d).cast<float>());
                  batch.colors.push_back(pixelColor(u, v));
                });
  return batch;
}

DepthFrame renderDepth(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_world_cam,
                       double max_depth_m, double noise_m, uint32_t seed) {
  DepthFrame frame;
  frame.width = camera.width;
  frame.height = camera.height;
  frame.fx = camera.fx;
  frame.fy = camera.fy;
  frame.cx = camera.cx;
  frame.cy = camera.cy;
  frame.T_world_cam = T_world_cam;
  frame.depth_m.assign(static_cast<size_t>(camera.width) * camera.height, std::numeric_limits<float>::quiet_NaN());
  frame.colors.resize(frame.depth_m.size());
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) frame.colors[static_cast<size_t>(v) * camera.width + u] = pixelColor(u, v);
  }
  castPixelRays(scene, camera, T_world_cam, max_depth_m, noise_m, seed,
                [&](int u, int v, const Eigen::Vector3d& d_cam, const Eigen::Vector3d&, double range_m) {
                  // z = range * cos(angle to the axis)
                  frame.depth_m[static_cast<size_t>(v) * camera.width + u] = static_cast<float>(range_m / d_cam.norm());
                });
  return frame;
}

PointBatch renderScan(const Scene& scene, const LaserScanner& scanner, const Eigen::Isometry3d& T_world_scanner,
                      double max_range_m, double noise_m, uint32_t seed) {
  PointBatch batch;
  batch.origin = T_world_scanner.translation();
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m > 0.0 ? noise_m : 1.0);
  batch.points.reserve(static_cast<size_t>(scanner.rings) * scanner.columns);
  for (int r = 0; r < scanner.rings; ++r) {
    const double elevation = scanner.rings == 1
                                 ? scanner.min_elevation_rad
                                 : scanner.min_elevation_rad +
                                       (scanner.max_elevation_rad - scanner.min_elevation_rad) * r / (scanner.rings - 1);
    for (int c = 0; c < scanner.columns; ++c) {
      const double azimuth = scanner.azimuth_offset_rad + 2.0 * M_PI * c / scanner.columns;
      const Eigen::Vector3d d_scanner(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                                      std::sin(elevation));
      const Eigen::Vector3d d = (T_world_scanner.linear() * d_scanner).normalized();
      const auto t = scene.intersect(batch.origin, d, max_range_m);
      if (!t) continue;
      const double range = *t + (noise_m > 0.0 ? noise(rng) : 0.0);
      batch.points.push_back((batch.origin + range * d).cast<float>());
    }
  }
  return batch;
}

Eigen::Isometry3d lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - position).normalized();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  if (std::fabs(z.dot(up)) > 0.99) up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = z.cross(up).normalized();  // image x to the right, image y down
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = position;
  return T;
}

}  // namespace cenote::mapping::test
