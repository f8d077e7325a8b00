// wreck_scene.cpp: a boxy steel hull with a deckhouse, bridge and mast, listing on a sandy floor
// among scattered debris; the vehicle circles it at a few metres' stand-off under natural light.
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
constexpr double kHalfLength_m = 7.0;             // hull along x
constexpr double kHalfBeam_m = 2.0;               // hull along y
constexpr double kBowStart_m = 4.0;               // x where the sides start to taper to the bow
constexpr double kKeel_m = -0.8;                  // hull bottom (buried)
constexpr double kDeck_m = 2.2;                   // deck height above the floor
constexpr double kStandOff_m = 3.2;               // path distance from the hull's sides
constexpr double kAltitude_m = 2.8;               // camera height above the floor
constexpr double kTilt_rad = 22.0 * kPi / 180.0;  // camera pitched down from horizontal

}  // namespace

SimScene buildWreck(const SimConfig& config, double path_length_m) {
  const auto seed = static_cast<uint64_t>(config.seed);
  const double cell = std::max(config.mesh_spacing_m, 0.1);  // flat faces need no fine tessellation
  MeshBuilder builder;

  // The hull lists by a few degrees and lies slightly turned; everything on it moves with it.
  const double list = (4.0 + 4.0 * hashToUnit(hash64(seed, 0x3EC, 0))) * kPi / 180.0;
  const double yaw = (hashToUnit(hash64(seed, 0x3EC, 1)) - 0.5) * 10.0 * kPi / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(list, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  auto hull = [&](double x, double y, double z) { return Eigen::Vector3d(R * Eigen::Vector3d(x, y, z)); };

  // Outline of the deck, counter-clockwise seen from above: square stern, tapered bow.
  const std::vector<Eigen::Vector2d> outline = {{-kHalfLength_m, -kHalfBeam_m},
                                                {kBowStart_m, -kHalfBeam_m},
                                                {kHalfLength_m, 0.0},
                                                {kBowStart_m, kHalfBeam_m},
                                                {-kHalfLength_m, kHalfBeam_m}};
  for (size_t i = 0; i < outline.size(); ++i) {
    const Eigen::Vector2d a = outline[i], b = outline[(i + 1) % outline.size()];
    builder.addQuad(hull(a.x(), a.y(), kKeel_m), hull(b.x(), b.y(), kKeel_m), hull(b.x(), b.y(), kDeck_m),
                    hull(a.x(), a.y(), kDeck_m), Material::kRust, cell);
  }
  // Deck: the stern rectangle and the bow triangle (both convex), split into a grid for culling.
  builder.addQuad(hull(-kHalfLength_m, -kHalfBeam_m, kDeck_m), hull(kBowStart_m, -kHalfBeam_m, kDeck_m),
                  hull(kBowStart_m, kHalfBeam_m, kDeck_m), hull(-kHalfLength_m, kHalfBeam_m, kDeck_m), Material::kHull,
                  cell);
  builder.addConvexPolygon({hull(kBowStart_m, -kHalfBeam_m, kDeck_m), hull(kHalfLength_m, 0.0, kDeck_m),
                            hull(kBowStart_m, kHalfBeam_m, kDeck_m)},
                           Material::kHull);
  auto box = [&](double x, double y, double z, double dx, double dy, double dz, Material m) {
    builder.addBox(hull(x, y, z), R * Eigen::Vector3d(dx, 0, 0), R * Eigen::Vector3d(0, dy, 0),
                   R * Eigen::Vector3d(0, 0, dz), m, cell);
  };
  box(-5.5, -1.3, kDeck_m, 3.5, 2.6, 1.6, Material::kHull);        // deckhouse
  box(-4.8, -1.0, kDeck_m + 1.6, 2.0, 2.0, 1.0, Material::kRust);  // bridge
  box(1.8, -0.12, kDeck_m, 0.24, 0.24, 3.0, Material::kRust);      // mast
  box(-0.8, -1.0, kDeck_m, 1.8, 2.0, 0.35, Material::kHull);       // hatch cover
  box(2.8, -0.8, kDeck_m, 0.9, 1.6, 0.3, Material::kRust);         // winch housing
  for (int k = 0; k < 6; ++k) {                                    // hull ribs, proud of the plating
    const double x = -6.0 + 2.0 * k;
    box(x, -kHalfBeam_m - 0.08, kKeel_m, 0.12, 0.08, kDeck_m - kKeel_m, Material::kRust);
    box(x, kHalfBeam_m, kKeel_m, 0.12, 0.08, kDeck_m - kKeel_m, Material::kRust);
  }

  // Sea floor: sand with ripples and a scour around the hull, scattered rocks and debris.
  const double extent_x = kHalfLength_m + kStandOff_m + 5.0, extent_y = kHalfBeam_m + kStandOff_m + 5.0;
  const double spacing = 1.6 * config.mesh_spacing_m;  // the sand is smoother than reef or rock
  const int nx = static_cast<int>(std::ceil(2 * extent_x / spacing)),
            ny = static_cast<int>(std::ceil(2 * extent_y / spacing));
  auto floor = [&](double x, double y) {
    return 0.25 * fbm3(x / 3.0, y / 3.0, 0.5, seed + 31, 3) + 0.06 * fbm3(x / 0.4, y / 0.4, 0.5, seed + 32, 3) +
           0.02 * std::sin(2.0 * kPi * (0.9 * x + 0.4 * y) / 0.5);
  };
  builder.addGrid(
      nx, ny,
      [&](int i, int j) {
        const double x = -extent_x + i * spacing, y = -extent_y + j * spacing;
        return Eigen::Vector3d(x, y, floor(x, y));
      },
      [&](int i, int j) {
        const double x = -extent_x + (i + 0.5) * spacing, y = -extent_y + (j + 0.5) * spacing;
        return fbm3(x / 2.0, y / 2.0, 1.0, seed + 33, 2) > 0.25 ? Material::kRock : Material::kSand;
      });
  for (int k = 0; k < 24; ++k) {
    const double angle = 2.0 * kPi * hashToUnit(hash64(seed, 0xDEB, k, 0));
    const double ring = 1.0 + 4.0 * hashToUnit(hash64(seed, 0xDEB, k, 1));
    const double x = (kHalfLength_m + ring) * std::cos(angle), y = (kHalfBeam_m + ring) * std::sin(angle);
    const double size = 0.2 + 0.6 * hashToUnit(hash64(seed, 0xDEB, k, 2));
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(angle * 3.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    builder.addBox(Eigen::Vector3d(x, y, floor(x, y) - 0.1), turn * Eigen::Vector3d(size, 0, 0),
                   turn * Eigen::Vector3d(0, 0.6 * size, 0), Eigen::Vector3d(0, 0, 0.4 * size + 0.1),
                   k % 3 == 0 ? Material::kRust : Material::kRock, cell);
  }

  SimScene scene = sceneWithMesh(SimSceneKind::kWreck, builder);
  scene.lighting = sunlitWater(config.turbidity, {0.13f, 0.10f, 0.45f}, {0.22f, 0.28f, 0.04f}, 14.0f,
                               {0.06f, 0.06f, 0.32f});

  // Counter-clockwise around the hull, which stays on the left; the camera looks left and down.
  const double px = kHalfLength_m + kStandOff_m, py = kHalfBeam_m + kStandOff_m;
  auto path = std::make_shared<RoundedPath>(std::vector<Eigen::Vector2d>{{-px, -py}, {px, -py}, {px, py}, {-px, py}}, 2.5);
  const double speed = config.speed_m_s;
  scene.T_world_cam0 = [path, speed](double t_s) {
    const double s = speed * t_s;
    const Eigen::Vector2d p = path->position(s), heading2 = path->tangent(s);
    const Eigen::Vector3d heading(heading2.x(), heading2.y(), 0.0);
    const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(heading);
    const Eigen::Vector3d forward = std::cos(kTilt_rad) * (0.9 * left + 0.3 * heading).normalized() -
                                    std::sin(kTilt_rad) * Eigen::Vector3d::UnitZ();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = lookRotation(forward, Eigen::Vector3d::UnitZ());
    T.translation() = Eigen::Vector3d(p.x(), p.y(), kAltitude_m + 0.15 * std::sin(0.25 * t_s));
    return T;
  };
  (void)path_length_m;  // the loop repeats for long sequences
  return scene;
}

}  // namespace cenote::sim::detail
