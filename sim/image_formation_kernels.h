// image_formation_kernels.h: the per-row SIMD kernels behind image_formation.h: Highway, compiled
// once per instruction set and chosen at run time. Internal to sim/.
//   shadeRadianceRow()  renderRadiance(): the model of sim_scene.h (SceneLighting) and
//                       image_formation.h (SurfaceTexture; the scalar surfaceAlbedo() is the
//                       reference for the texture part)
//   exposeRow()         exposeImage(): gain, gamma, sensor noise, 8-bit
// Units: metres, pixels, texels. Frame: vectors are offsets from the camera centre along world axes
// (float stays precise: the absolute position enters only through per-call constants).
// Threads: a pure function of its arguments; each call writes only its own output row. A pixel's
// result does not depend on its lane or on how rows are shared between threads.
#pragma once

#include <cstdint>

#include "sim/scene_mesh.h"

namespace cenote::sim::detail {

// One NoiseTexture layer of the surface texture (NoiseTexture::quads() layout).
struct TextureLayer {
  const uint32_t* quads = nullptr;
  const int32_t* level_offsets = nullptr;
  int size_log2 = 0, levels = 0;
  float texels_per_m = 0.0f;
  // Texel coordinates of the camera centre in each TexturePlane (index = plane), wrapped into
  // [0, size) and including the layer's shift.
  float origin_u[3] = {}, origin_v[3] = {};
};

// Everything the shader needs for one camera image, resolved once per call.
struct RadianceSetup {
  int width = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0;
  float R[9] = {};                                           // camera to world rotation, row-major
  const float* normals = nullptr;                            // SceneMesh::normals, 3 floats per triangle
  const int32_t* shading_codes = nullptr;                    // SceneMesh::shading_codes
  float albedo[3][static_cast<int>(Material::kCount)] = {};  // base colour per channel (B, G, R), material
  TextureLayer fine, coarse;
  float beta[3] = {}, backscatter[3] = {};  // per channel, SceneLighting
  bool rig_light = false;
  float lamp[3] = {};       // lamp position minus camera centre, world axes
  float lamp_axis[3] = {};  // unit, world
  float rig_intensity = 0.0f;
  bool sun = false;
  float sun_irradiance[3] = {}, downwelling[3] = {};
  float surface_above_camera_m = 0.0f;  // water surface z minus camera centre z
  float ambient = 0.0f;
};

// Linear BGR radiance (3 floats per pixel) of row y: ids and depth are the row of the visibility
// buffer (triangle -1: no surface, the water's backscatter).
void shadeRadianceRow(const RadianceSetup& setup, int y, const int32_t* ids, const float* depth, float* out_bgr);

// Constants of sensorNoise(): multipliers of the hash (MurmurHash3's finaliser after a golden-ratio
// multiply), and the mean and standard deviation of the sum of four uniform bytes.
inline constexpr uint32_t kNoiseMul0 = 0x9E3779B1u, kNoiseMul1 = 0x85EBCA6Bu, kNoiseMul2 = 0xC2B2AE35u;
inline constexpr float kNoiseMean = 510.0f;
inline constexpr float kNoiseScale = 1.0f / 147.80054f;  // 1 / sqrt(4 (256^2 - 1) / 12)

// Sensor noise of sample i (pixel * 3 + channel, counted from the image's first pixel) for the
// image key `key`: approximately standard normal (sum of the four bytes of a 32-bit hash,
// centred and scaled: |n| <= 3.45).
float sensorNoise(uint64_t key, uint32_t i);

// out[k] = round(255 (gain in[k])^(1/2.2) + noise_sigma sensorNoise(key, first + k)) clipped to
// [0, 255], for k in [0, count); gamma_table[j] = 255 (j / gamma_levels)^(1/2.2), j in [0, gamma_levels].
void exposeRow(const float* in, int count, uint32_t first, float gain, float noise_sigma, uint64_t key,
               const float* gamma_table, int gamma_levels, uint8_t* out);

}  // namespace cenote::sim::detail
