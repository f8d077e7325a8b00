// reef_scene.cpp: a rough sea floor (heightfield with rocks, coral heads and sponges) surveyed in
// lawnmower passes at a few metres altitude under natural light from above.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "sim/procedural_noise.h"
#include "sim/rounded_path.h"
#include "sim/sim_scene.h"

namespace cenote::sim::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRowLength_m = 8.0;
constexpr double kRowSpacing_m = 1.6;
constexpr int kRows = 4;
constexpr double kAltitude_m = 2.6;               // camera height above the mean floor (z = 0)
constexpr double kMargin_m = 6.0;                 // floor beyond the path, what the tilted camera sees
constexpr double kTilt_rad = 25.0 * kPi / 180.0;  // camera pitched forward from straight down

struct CoralHead {
  Eigen::Vector2d center;
  double radius_m, height_m;
  bool sponge;
};

}  // namespace

SimScene buildReef(const SimConfig& config, double path_length_m) {
  const auto seed = static_cast<uint64_t>(config.seed);
  // Closed lawnmower loop: rows along x, a return leg at x = -0.8.
  std::vector<Eigen::Vector2d> waypoints;
  for (int r = 0; r < kRows; ++r) {
    const double y = r * kRowSpacing_m;
    if (r % 2 == 0) {
      waypoints.emplace_back(r == 0 ? 0.0 : 0.0, y);
      waypoints.emplace_back(kRowLength_m, y);
    } else {
      waypoints.emplace_back(kRowLength_m, y);
      waypoints.emplace_back(0.0, y);
    }
  }
  waypoints.back().x() = -0.8;
  waypoints.emplace_back(-0.8, 0.0);
  auto path = std::make_shared<RoundedPath>(waypoints, 0.4);

  const double x0 = -0.8 - kMargin_m, x1 = kRowLength_m + kMargin_m;
  const double y0 = -kMargin_m, y1 = (kRows - 1) * kRowSpacing_m + kMargin_m;
  std::vector<CoralHead> heads;
  const int num_heads = static_cast<int>((x1 - x0) * (y1 - y0) * 0.35);
  for (int i = 0; i < num_heads; ++i) {
    CoralHead h;
    h.center = {x0 + (x1 - x0) * hashToUnit(hash64(seed, 0xC0, i, 0)),
                y0 + (y1 - y0) * hashToUnit(hash64(seed, 0xC0, i, 1))};
    h.radius_m = 0.2 + 0.5 * hashToUnit(hash64(seed, 0xC0, i, 2));
    h.height_m = h.radius_m * (0.5 + 0.9 * hashToUnit(hash64(seed, 0xC0, i, 3)));
    h.sponge = hashToUnit(hash64(seed, 0xC0, i, 4)) < 0.3;
    heads.push_back(h);
  }
  // Coral heads on a coarse grid for lookup.
  constexpr double kCell_m = 1.0;
  const int gx = static_cast<int>(std::ceil((x1 - x0) / kCell_m)), gy = static_cast<int>(std::ceil((y1 - y0) / kCell_m));
  std::vector<std::vector<int>> grid(static_cast<size_t>(gx * gy));
  for (int i = 0; i < num_heads; ++i) {
    const CoralHead& h = heads[i];
    const int ax = std::max(0, static_cast<int>((h.center.x() - h.radius_m - x0) / kCell_m));
    const int bx = std::min(gx - 1, static_cast<int>((h.center.x() + h.radius_m - x0) / kCell_m));
    const int ay = std::max(0, static_cast<int>((h.center.y() - h.radius_m - y0) / kCell_m));
    const int by = std::min(gy - 1, static_cast<int>((h.center.y() + h.radius_m - y0) / kCell_m));
    for (int y = ay; y <= by; ++y)
      for (int x = ax; x <= bx; ++x) grid[static_cast<size_t>(y * gx + x)].push_back(i);
  }
  // Height of the coral at (x, y) and whether a sponge made it.
  auto coral = [&](double x, double y, bool* sponge) {
    const int cx = std::clamp(static_cast<int>((x - x0) / kCell_m), 0, gx - 1);
    const int cy = std::clamp(static_cast<int>((y - y0) / kCell_m), 0, gy - 1);
    double best = 0.0;
    for (int i : grid[static_cast<size_t>(cy * gx + cx)]) {
      const CoralHead& h = heads[i];
      const double r2 = (Eigen::Vector2d(x, y) - h.center).squaredNorm() / (h.radius_m * h.radius_m);
      if (r2 >= 1.0) continue;
      const double bumps = 1.0 + 0.25 * fbm3(x / 0.07, y / 0.07, i, seed + 21, 2);
      const double z = h.height_m * (1.0 - r2) * (1.0 - r2) * bumps;
      if (z > best) {
        best = z;
        if (sponge) *sponge = h.sponge;
      }
    }
    return best;
  };
  auto ground = [&](double x, double y) {
    return 0.35 * fbm3(x / 4.0, y / 4.0, 0.5, seed + 22, 3) + 0.10 * fbm3(x / 0.6, y / 0.6, 0.5, seed + 23, 4) +
           0.015 * std::sin(2.0 * kPi * (x * 0.8 + y * 0.6) / 0.3);  // sand ripples
  };
  const double spacing = config.mesh_spacing_m;
  const int nx = static_cast<int>(std::ceil((x1 - x0) / spacing)), ny = static_cast<int>(std::ceil((y1 - y0) / spacing));
  MeshBuilder builder;
  builder.addGrid(
      nx, ny,
      [&](int i, int j) {
        const double x = x0 + i * spacing, y = y0 + j * spacing;
        return Eigen::Vector3d(x, y, ground(x, y) + coral(x, y, nullptr));
      },
      [&](int i, int j) {
        const double x = x0 + (i + 0.5) * spacing, y = y0 + (j + 0.5) * spacing;
        bool sponge = false;
        if (coral(x, y, &sponge) > 0.03) return sponge ? Material::kSponge : Material::kCoral;
        return fbm3(x / 1.5, y / 1.5, 2.0, seed + 24, 2) > 0.1 ? Material::kRock : Material::kSand;
      });

  SimScene scene = sceneWithMesh(SimSceneKind::kReef, builder);
  scene.lighting = sunlitWater(config.turbidity, {0.10f, 0.09f, 0.42f}, {0.30f, 0.24f, 0.03f}, 10.0f,
                               {0.05f, 0.06f, 0.30f});

  const double speed = config.speed_m_s;
  scene.T_world_cam0 = [path, speed](double t_s) {
    const double s = speed * t_s;
    const Eigen::Vector2d p = path->position(s), heading2 = path->tangent(s);
    const Eigen::Vector3d heading(heading2.x(), heading2.y(), 0.0);
    const Eigen::Vector3d forward = -std::cos(kTilt_rad) * Eigen::Vector3d::UnitZ() + std::sin(kTilt_rad) * heading;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = lookRotation(forward, heading) *
                 Eigen::AngleAxisd(0.03 * std::sin(0.5 * t_s), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(p.x(), p.y(), kAltitude_m + 0.1 * std::sin(0.3 * t_s));
    return T;
  };
  (void)path_length_m;  // the loop repeats for long sequences
  return scene;
}

}  // namespace cenote::sim::detail
