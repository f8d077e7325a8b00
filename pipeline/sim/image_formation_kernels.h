// radiance_kernels.h: the per-row SIMD shader behind renderRadiance() (image_formation.h): Highway,
// compiled once per instruction set and chosen at run time. Internal to pipeline/sim; the model it
// evaluates is documented in sim_scene.h (SceneLighting) and image_formation.h (SurfaceTexture),
// whose scalar surfaceAlbedo() is the reference for the texture part.
// Units: metres, pixels, texels. Frame: vectors are offsets from the camera centre along world axes
// (float stays precise: the absolute position enters only through per-call constants).
// Threads: a pure function of its arguments; each call writes only its own output row. A pixel's
// result does not depend on its lane or on how rows are shared between threads.
#pragma once

#include <cstdint>

#include "pipeline/sim/scene_mesh.h"

namespace cenote::pipeline::detail {

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
  float R[9] = {};  // camera to world rotation, row-major
  const float* normals = nullptr;          // SceneMesh::normals, 3 floats per triangle
  const int32_t* shading_codes = nullptr;  // SceneMesh::shading_codes
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

}  // namespace cenote::pipeline::detail
