// sim_scene.h: the three simulated worlds (cave, reef, wreck): geometry, materials, water and light,
// and the trajectory the left camera follows through them.
// Units: metres, seconds; colours are linear BGR reflectances / radiances in [0, 1]-ish.
// Frames: world z up. Cameras look along their +z, x right, y down (T_world_cam).
// Threads: a SimScene is immutable after buildScene(); T_world_cam0 is a pure function.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <functional>

#include "sim/scene_mesh.h"
#include "sim/sim_config.h"

namespace cenote::sim {

// Light and water of a scene. Per channel c (B, G, R), a surface point at range r from the camera
// with reflectance rho_c under irradiance E_c appears as
//   J_c = rho_c E_c exp(-beta_c r) + B_c (1 - exp(-beta_c r))      (attenuation + backscatter)
// with E_c the sum of
//   rig light:  I cos^2(angle off the lamp axis) max(0, n.l) exp(-beta_c d) / d^2   (d: lamp to surface)
//   sun:        S_c exp(-Kd_c depth_below_surface) (ambient + (1 - ambient) max(0, n.z))
struct SceneLighting {
  Eigen::Array3f attenuation_per_m = {0.06f, 0.08f, 0.40f};  // beta_c (B, G, R): red fades first
  Eigen::Array3f backscatter = {0.0f, 0.0f, 0.0f};           // B_c, veiling light at infinite range
  bool rig_light = false;
  Eigen::Vector3d light_in_cam0 = {0.0, -0.15, 0.0};  // light position on the rig, cam0 frame
  float rig_intensity = 1.0f;                         // I, at 1 m on axis
  bool sun = false;
  Eigen::Array3f sun_irradiance = {1.0f, 1.0f, 1.0f};        // S_c just below the water surface
  Eigen::Array3f downwelling_per_m = {0.05f, 0.07f, 0.35f};  // Kd_c
  float surface_z_m = 10.0f;                                 // world z of the water surface
  float ambient = 0.35f;                                     // share of sunlight that is diffuse
};

struct SimScene {
  SimSceneKind kind = SimSceneKind::kCave;
  SceneMesh mesh;
  SceneLighting lighting;
  std::array<Eigen::Array3f, static_cast<size_t>(Material::kCount)> albedo;  // BGR base reflectance
  // Pose of the left camera at t seconds after the first frame (smooth in t).
  std::function<Eigen::Isometry3d(double)> T_world_cam0;
};

// Builds the scene `config.scene`, large enough for config.num_frames at config.speed_m_s plus what
// the cameras see ahead. Geometry and texture depend on config.seed.
// @throws cenote::Error for an invalid config.
SimScene buildScene(const SimConfig& config);

// Camera looking along `forward` with image-down as close as possible to world -z (for a
// down-looking camera, image-up along `up_hint`).
Eigen::Matrix3d lookRotation(const Eigen::Vector3d& forward, const Eigen::Vector3d& up_hint);

namespace detail {
SimScene buildCave(const SimConfig& config, double path_length_m);
SimScene buildReef(const SimConfig& config, double path_length_m);
SimScene buildWreck(const SimConfig& config, double path_length_m);
// The scene of `kind` with the builder's mesh (builder.finish()) and every material's default albedo;
// its lighting is the caller's to set.
SimScene sceneWithMesh(SimSceneKind kind, MeshBuilder& builder);
// Open water lit by the sun (reef, wreck): attenuation and downwelling scale with turbidity, the
// backscatter with min(1, turbidity) and a 0.35 share; no rig light.
SceneLighting sunlitWater(double turbidity, const Eigen::Array3f& attenuation_per_m, const Eigen::Array3f& backscatter,
                          float surface_z_m, const Eigen::Array3f& downwelling_per_m);
}  // namespace detail

}  // namespace cenote::sim
