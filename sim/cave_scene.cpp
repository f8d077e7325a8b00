// cave_scene.cpp: an enclosed, winding tunnel of varying radius with rough walls and a sandy floor;
// the only light is the one the diver carries on the rig.
#include <algorithm>
#include <cmath>

#include "sim/procedural_noise.h"
#include "sim/sim_scene.h"

namespace cenote::sim::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kBehindStart_m = 2.5;  // tunnel behind the first pose
constexpr double kAheadOfEnd_m = 10.0;  // tunnel beyond the last pose (the light reaches ~6 m)
constexpr double kTaper_m = 1.5;        // the tunnel closes over this length at both ends
constexpr double kMaxRadius_m = 2.6;    // bounds the tessellation around the tunnel

struct Tunnel {
  uint64_t seed;
  double phase[4];

  Eigen::Vector3d center(double s) const {
    return {s, 1.5 * std::sin(s / 5.0 + phase[0]) + 0.6 * std::sin(s / 2.2 + phase[1]), 0.5 * std::sin(s / 3.5 + phase[2])};
  }
  // Unit tangent, right-hand side and up of the centreline (world z is never along the tunnel).
  void frame(double s, Eigen::Vector3d& tangent, Eigen::Vector3d& side, Eigen::Vector3d& up) const {
    tangent = (center(s + 1e-4) - center(s - 1e-4)).normalized();
    side = tangent.cross(Eigen::Vector3d::UnitZ()).normalized();
    up = side.cross(tangent);
  }
  double radius(double s) const { return 1.8 + 0.4 * std::sin(s / 3.7 + phase[3]); }
};

double smoothstep(double a, double b, double x) {
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace

SimScene buildCave(const SimConfig& config, double path_length_m) {
  const auto seed = static_cast<uint64_t>(config.seed);
  Tunnel tunnel{seed, {}};
  for (int i = 0; i < 4; ++i) tunnel.phase[i] = 2.0 * kPi * hashToUnit(hash64(seed, 0xCA7E, i));
  const double s0 = -kBehindStart_m, s1 = path_length_m + kAheadOfEnd_m;
  const double spacing = config.mesh_spacing_m;
  const int nu = static_cast<int>(std::ceil(2.0 * kPi * kMaxRadius_m / spacing));
  const int nv = static_cast<int>(std::ceil((s1 - s0) / spacing));

  // The floor is where the cross-section is flattened; remember it for the materials.
  auto vertical = [](double v, double floor) {
    constexpr double k = 0.12;  // softness of the floor's edge, metres
    return floor + k * std::log1p(std::exp((v - floor) / k));
  };
  auto position = [&](int i, int j) -> Eigen::Vector3d {
    const double s = s0 + (s1 - s0) * j / nv;
    const double theta = 2.0 * kPi * i / nu;
    Eigen::Vector3d t, side, up;
    tunnel.frame(s, t, side, up);
    const Eigen::Vector3d c = tunnel.center(s);
    const double r0 = tunnel.radius(s);
    const Eigen::Vector3d q = c + r0 * (std::cos(theta) * side + std::sin(theta) * up);
    const double taper = std::max(0.01, smoothstep(s0, s0 + kTaper_m, s) * (1.0 - smoothstep(s1 - kTaper_m, s1, s)));
    const double rough = 1.0 + 0.12 * fbm3(q.x() / 0.9, q.y() / 0.9, q.z() / 0.9, seed + 11, 4) +
                         0.04 * fbm3(q.x() / 0.2, q.y() / 0.2, q.z() / 0.2, seed + 12, 3);
    const double r = r0 * rough * taper;
    const double floor = -0.62 * r0 * taper + 0.06 * fbm3(q.x() / 0.5, q.y() / 0.5, 0.0, seed + 13, 3);
    return c + r * std::cos(theta) * side + vertical(r * std::sin(theta), floor) * up;
  };
  auto material = [&](int i, int j) {
    const double theta = 2.0 * kPi * (i + 0.5) / nu;
    // The lower part of the section is the sediment floor.
    if (std::sin(theta) < -0.55) return Material::kSand;
    const double s = s0 + (s1 - s0) * (j + 0.5) / nv;
    const double patch = fbm3(s / 1.3, std::cos(theta) * 1.5, std::sin(theta) * 1.5, seed + 14, 2);
    return patch > 0.35 ? Material::kSponge : Material::kRock;
  };
  MeshBuilder builder;
  // The winding faces the inside of the tunnel (the rasteriser draws only that side): d/dtheta x d/ds
  // points to the centreline (at theta = 0, up x tangent = -side).
  builder.addGrid(nu, nv, position, material, /*wrap_u=*/true);

  SimScene scene = sceneWithMesh(SimSceneKind::kCave, builder);
  SceneLighting& light = scene.lighting;
  light.attenuation_per_m = Eigen::Array3f(0.05f, 0.07f, 0.38f) * static_cast<float>(config.turbidity);
  light.backscatter = Eigen::Array3f(0.010f, 0.012f, 0.004f) * static_cast<float>(std::min(1.0, config.turbidity));
  light.rig_light = true;
  light.light_in_cam0 = {0.06, -0.18, 0.05};
  light.rig_intensity = 1.0f;
  light.sun = false;

  const double speed = config.speed_m_s;
  const double phase_x = 2.0 * kPi * hashToUnit(hash64(seed, 0xCA7E, 7));
  scene.T_world_cam0 = [tunnel, speed, phase_x](double t_s) {
    const double s = speed * t_s;
    Eigen::Vector3d tangent, side, up;
    tunnel.frame(s, tangent, side, up);
    const double r = tunnel.radius(s);
    const Eigen::Vector3d offset = 0.18 * r * std::sin(0.45 * t_s + phase_x) * side + 0.12 * r * std::sin(0.33 * t_s) * up;
    Eigen::Vector3d ahead_t, ahead_side, ahead_up;
    tunnel.frame(s + 1.8, ahead_t, ahead_side, ahead_up);
    const Eigen::Vector3d position = tunnel.center(s) + offset;
    const Eigen::Vector3d target = tunnel.center(s + 1.8) + 0.3 * offset;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = lookRotation(target - position, up) *
                 Eigen::AngleAxisd(0.05 * std::sin(0.4 * t_s), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = position;
    return T;
  };
  return scene;
}

}  // namespace cenote::sim::detail
