#include "sim/sim_scene.h"

#include "common/error.h"

namespace cenote::sim {

Eigen::Matrix3d lookRotation(const Eigen::Vector3d& forward, const Eigen::Vector3d& up_hint) {
  const Eigen::Vector3d z = forward.normalized();
  Eigen::Vector3d up = up_hint - up_hint.dot(z) * z;
  if (up.norm() < 1e-9) throw Error("lookRotation: forward is parallel to the up hint");
  const Eigen::Vector3d y = -up.normalized();
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return R;
}

namespace detail {

SceneLighting sunlitWater(double turbidity, const Eigen::Array3f& attenuation_per_m, const Eigen::Array3f& backscatter,
                          float surface_z_m, const Eigen::Array3f& downwelling_per_m) {
  const auto t = static_cast<float>(turbidity);
  SceneLighting light;
  light.attenuation_per_m = attenuation_per_m * t;
  light.backscatter = backscatter * std::min(1.0f, t) * 0.35f;
  light.sun = true;
  light.surface_z_m = surface_z_m;
  light.downwelling_per_m = downwelling_per_m * t;
  light.rig_light = false;
  return light;
}

SimScene sceneWithMesh(SimSceneKind kind, MeshBuilder& builder) {
  SimScene scene;
  scene.kind = kind;
  scene.mesh = builder.finish();
  auto set = [&](Material m, float b, float g, float r) { scene.albedo[static_cast<size_t>(m)] = {b, g, r}; };
  set(Material::kRock, 0.50f, 0.55f, 0.60f);    // limestone grey-beige
  set(Material::kSand, 0.62f, 0.72f, 0.78f);    // pale sand
  set(Material::kCoral, 0.45f, 0.50f, 0.85f);   // pink-orange coral
  set(Material::kSponge, 0.30f, 0.65f, 0.75f);  // yellow sponge
  set(Material::kHull, 0.45f, 0.50f, 0.42f);    // grey-green painted steel
  set(Material::kRust, 0.22f, 0.35f, 0.60f);    // rust brown
  return scene;
}

}  // namespace detail

SimScene buildScene(const SimConfig& config) {
  throwIfInvalid(config.validate(), "sim");
  const double duration_s = config.num_frames / config.rate_hz;
  const double path_length_m = config.speed_m_s * duration_s;
  switch (config.scene) {
    case SimSceneKind::kCave: return detail::buildCave(config, path_length_m);
    case SimSceneKind::kReef: return detail::buildReef(config, path_length_m);
    case SimSceneKind::kWreck: return detail::buildWreck(config, path_length_m);
  }
  throw Error("sim: unknown scene");
}

}  // namespace cenote::sim
