// image_formation.h: what an underwater camera records of the visible surfaces.
//   surfaceAlbedo():   view-independent texture (noise in world coordinates, several octaves,
//                      mip-filtered by the pixel footprint) times the material's base colour
//   renderRadiance():  linear BGR radiance per pixel: light (rig lamp with fall-off, or sunlight
//                      fading with depth), per-channel attenuation along the path, backscatter
//                      (the model is in sim_scene.h, SceneLighting)
//   exposeImage():     camera gain, gamma 1/2.2, seeded Gaussian sensor noise, 8-bit quantisation
//   renderImage():     both at once, row by row
// Units: metres, pixels; radiance is relative (exposeImage's gain maps it to [0, 1]).
// Threads: OpenMP over rows; results are bit-identical whatever the thread count (noise comes from
// a counter-based hash of seed and pixel, never from a shared generator).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>

#include "sim/procedural_noise.h"
#include "sim/rasterizer.h"
#include "sim/sim_scene.h"

namespace cenote::sim {

// Surface texture: a fine layer (4 mm texels, period 2 m) plus a coarse one (29 mm, period 7.4 m),
// so that the sum does not repeat within a scene. Small enough to stay in cache.
// A surface point's reflectance is the material's base colour times
//   kMinShade + (1 - kMinShade) clamp(0.5 + kContrast (kFineWeight fine + (1 - kFineWeight) coarse - 0.5), 0, 1)
// with the layers sampled at its texture-plane coordinates (texturePlane(), scene_mesh.h), the coarse
// one shifted by (kCoarseShiftU, kCoarseShiftV) texels so that the layers' origins do not line up.
struct SurfaceTexture {
  static constexpr int kFineSize = 512, kCoarseSize = 256;
  static constexpr double kFineTexel_m = 0.004, kCoarseTexel_m = 0.029;
  static constexpr float kCoarseShiftU = 37.1f, kCoarseShiftV = 91.7f;
  static constexpr float kFineWeight = 0.55f, kContrast = 1.4f, kMinShade = 0.15f;
  explicit SurfaceTexture(uint64_t seed);
  NoiseTexture fine, coarse;
};

// Reflectance (BGR, linear) of world point p on mesh triangle `triangle`, filtered over a pixel
// footprint of footprint_m metres (0: finest detail).
Eigen::Array3f surfaceAlbedo(const SimScene& scene, const SurfaceTexture& texture, const Eigen::Vector3f& p_world,
                             int triangle, float footprint_m);

// @param T_world_light pose of the rig (cam0) that carries the lamp (SceneLighting::light_in_cam0,
//        shining along cam0's +z); unused without a rig light.
// @return CV_32FC3 linear BGR radiance; pixels without a surface see the water's backscatter.
cv::Mat renderRadiance(const SimScene& scene, const SurfaceTexture& texture, const PinholeCamera& camera,
                       const Eigen::Isometry3d& T_world_cam, const VisibilityBuffer& visibility,
                       const Eigen::Isometry3d& T_world_light);

// exposeImage(renderRadiance(...), gain, noise_sigma, noise_seed), the same bytes, row by row: no
// radiance image in memory (what the simulator records when the rig has no distortion).
cv::Mat renderImage(const SimScene& scene, const SurfaceTexture& texture, const PinholeCamera& camera,
                    const Eigen::Isometry3d& T_world_cam, const VisibilityBuffer& visibility,
                    const Eigen::Isometry3d& T_world_light, float gain, float noise_sigma, uint64_t noise_seed);

// @return CV_8UC3: round(255 * (gain * radiance)^(1/2.2) + noise_sigma * n), clipped to [0, 255],
//         n approximately standard normal per pixel and channel (sensorNoise() of
//         image_formation_kernels.h: a hash of noise_seed and the sample's index, |n| <= 3.45).
cv::Mat exposeImage(const cv::Mat& radiance, float gain, float noise_sigma, uint64_t noise_seed);

// Gain that maps the given percentile (0-100) of the brightest channel of the surface pixels
// (triangle >= 0) to `target` (linear). 1 when no pixel has a surface.
float autoExposureGain(const cv::Mat& radiance, const VisibilityBuffer& visibility, double percentile, float target);

}  // namespace cenote::sim
