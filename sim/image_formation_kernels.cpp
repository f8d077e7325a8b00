// image_formation_kernels.cpp: Highway implementation of image_formation_kernels.h, compiled once per
// instruction set. Shading: every lane is one pixel; per-triangle data (normal, material, texture
// plane) and texture taps are gathered, a texture tap being one 32-bit gather of a texel's 2 x 2
// neighbourhood. Exposure: every lane is one sample (pixel channel); its noise is a hash of its index.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sim/image_formation_kernels.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cstring>

#include "sim/image_formation.h"
#include "sim/image_formation_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::sim::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;
using DI = hn::RebindToSigned<DF>;
using VF = hn::Vec<DF>;
using VI = hn::Vec<DI>;
using MF = hn::Mask<DF>;

constexpr float kMinViewCosine = 0.2f;  // the footprint of grazing views is capped at 5x

using DU = hn::RebindToUnsigned<DF>;
using VU = hn::Vec<DU>;

// exp(x) for x <= 0 to ~2e-4 relative: 2^(x log2 e) split into integer and fraction.
HWY_INLINE VF fastExp(DF df, VF x) {
  const DI di;
  const VF t = hn::Mul(hn::Max(x, hn::Set(df, -80.0f)), hn::Set(df, 1.44269504f));
  const VF whole = hn::Floor(t);
  const VF f = hn::Sub(t, whole);
  VF p = hn::MulAdd(hn::Set(df, 0.001333355f), f, hn::Set(df, 0.009618129f));
  p = hn::MulAdd(p, f, hn::Set(df, 0.05550411f));
  p = hn::MulAdd(p, f, hn::Set(df, 0.2402265f));
  p = hn::MulAdd(p, f, hn::Set(df, 0.6931472f));
  p = hn::MulAdd(p, f, hn::Set(df, 1.0f));
  const VI exponent = hn::ShiftLeft<23>(hn::Add(hn::ConvertTo(di, whole), hn::Set(di, 127)));
  return hn::Mul(p, hn::BitCast(df, exponent));
}

// log2(x) for x > 0: detail::kLog2Poly (procedural_noise.h).
HWY_INLINE VF fastLog2(DF df, VF x) {
  const DI di;
  const VI bits = hn::BitCast(di, x);
  const VF exponent = hn::ConvertTo(df, hn::Sub(hn::ShiftRight<23>(bits), hn::Set(di, 127)));
  const VF m = hn::BitCast(df, hn::Or(hn::And(bits, hn::Set(di, 0x007FFFFF)), hn::Set(di, 0x3F800000)));
  const VF poly = hn::MulAdd(hn::MulAdd(hn::Set(df, kLog2Poly[0]), m, hn::Set(df, kLog2Poly[1])), m,
                             hn::Set(df, kLog2Poly[2]));
  return hn::Add(exponent, poly);
}

// NoiseTexture::bilinear at a per-lane mip level.
HWY_INLINE VF bilinear(DF df, const TextureLayer& tex, VI level, VF u, VF v) {
  const DI di;
  const VI n = hn::Set(di, 1 << tex.size_log2) >> level;
  const VI mask = hn::Sub(n, hn::Set(di, 1));
  const VF scale = hn::BitCast(df, hn::ShiftLeft<23>(hn::Sub(hn::Set(di, 127), level)));  // 2^-level
  const VF half = hn::Set(df, 0.5f);
  const VF x = hn::MulSub(hn::Add(u, half), scale, half), y = hn::MulSub(hn::Add(v, half), scale, half);
  const VF fx = hn::Floor(x), fy = hn::Floor(y);
  const VF tx = hn::Sub(x, fx), ty = hn::Sub(y, fy);
  const VI x0 = hn::And(hn::ConvertTo(di, fx), mask), y0 = hn::And(hn::ConvertTo(di, fy), mask);
  const VI index = hn::Add(hn::GatherIndex(di, tex.level_offsets, level), hn::Add(hn::Mul(y0, n), x0));
  const VI q = hn::GatherIndex(di, reinterpret_cast<const int32_t*>(tex.quads), index);
  const VI byte = hn::Set(di, 0xFF);
  const VF t00 = hn::ConvertTo(df, hn::And(q, byte)), t10 = hn::ConvertTo(df, hn::And(hn::ShiftRight<8>(q), byte));
  const VF t01 = hn::ConvertTo(df, hn::And(hn::ShiftRight<16>(q), byte));
  const VF t11 = hn::ConvertTo(df, hn::And(hn::ShiftRight<24>(q), byte));
  const VF a = hn::MulAdd(hn::Sub(t10, t00), tx, t00);
  const VF b = hn::MulAdd(hn::Sub(t11, t01), tx, t01);
  return hn::Mul(hn::MulAdd(hn::Sub(b, a), ty, a), hn::Set(df, 1.0f / 255.0f));
}

// NoiseTexture::sample: trilinear between the two mip levels around log2 of the footprint.
HWY_INLINE VF sampleTexture(DF df, const TextureLayer& tex, VF u, VF v, VF footprint_texels) {
  const DI di;
  const VF period = hn::Set(df, static_cast<float>(1 << tex.size_log2));
  const VF inverse_period = hn::Set(df, 1.0f / static_cast<float>(1 << tex.size_log2));
  u = hn::NegMulAdd(period, hn::Floor(hn::Mul(u, inverse_period)), u);
  v = hn::NegMulAdd(period, hn::Floor(hn::Mul(v, inverse_period)), v);
  const VF max_lod = hn::Set(df, static_cast<float>(tex.levels - 1) - 1e-3f);
  const VF lod = hn::Max(hn::Zero(df), hn::Min(fastLog2(df, hn::Max(footprint_texels, hn::Set(df, 1.0f))), max_lod));
  const VI level = hn::ConvertTo(di, lod);
  const VF t = hn::Sub(lod, hn::ConvertTo(df, level));
  const VF a = bilinear(df, tex, level, u, v);
  if (hn::AllTrue(df, hn::Eq(t, hn::Zero(df)))) return a;  // all at level 0 (near surfaces)
  const VF b = bilinear(df, tex, hn::Add(level, hn::Set(di, 1)), u, v);
  return hn::MulAdd(hn::Sub(b, a), t, a);
}

// Per-lane pick of value[plane] for plane in {0, 1, 2}.
HWY_INLINE VF byPlane(DF df, VI plane, const float value[3]) {
  const DI di;
  const VF v12 = hn::IfThenElse(hn::RebindMask(df, hn::Eq(plane, hn::Set(di, 1))), hn::Set(df, value[1]),
                                hn::Set(df, value[2]));
  return hn::IfThenElse(hn::RebindMask(df, hn::Eq(plane, hn::Zero(di))), hn::Set(df, value[0]), v12);
}

// Radiance of `lanes` pixels starting at column x of row y (ray_y = (y - cy) / fy).
HWY_INLINE void shadePixels(const RadianceSetup& s, int x, float ray_y, const int32_t* ids, const float* depth,
                            float* out) {
  const DF df;
  const DI di;
  const VI id = hn::LoadU(di, ids);
  const MF valid = hn::RebindMask(df, hn::Gt(id, hn::Set(di, -1)));
  const VF b0 = hn::Set(df, s.backscatter[0]), b1 = hn::Set(df, s.backscatter[1]), b2 = hn::Set(df, s.backscatter[2]);
  if (hn::AllFalse(df, valid)) {
    hn::StoreInterleaved3(b0, b1, b2, df, out);
    return;
  }
  const VI tri = hn::IfThenElseZero(hn::RebindMask(di, valid), id);
  const VF z = hn::IfThenElse(valid, hn::LoadU(df, depth), hn::Set(df, 1.0f));

  // The point relative to the camera centre: camera frame, then world axes.
  const VF ray_x = hn::Div(hn::Sub(hn::Iota(df, static_cast<float>(x)), hn::Set(df, s.cx)), hn::Set(df, s.fx));
  const VF px = hn::Mul(ray_x, z), py = hn::Mul(hn::Set(df, ray_y), z);
  const VF range = hn::Sqrt(hn::MulAdd(px, px, hn::MulAdd(py, py, hn::Mul(z, z))));
  auto rotate = [&](int row) {
    return hn::MulAdd(hn::Set(df, s.R[3 * row]), px,
                      hn::MulAdd(hn::Set(df, s.R[3 * row + 1]), py, hn::Mul(hn::Set(df, s.R[3 * row + 2]), z)));
  };
  const VF ox = rotate(0), oy = rotate(1), oz = rotate(2);
  const VF inverse_range = hn::Div(hn::Set(df, 1.0f), range);
  const VF vx = hn::Mul(ox, inverse_range), vy = hn::Mul(oy, inverse_range), vz = hn::Mul(oz, inverse_range);

  // Normal facing the camera; the texture footprint grows as the view grazes the surface.
  const VI tri3 = hn::Mul(tri, hn::Set(di, 3));
  VF nx = hn::GatherIndex(df, s.normals, tri3);
  VF ny = hn::GatherIndex(df, s.normals, hn::Add(tri3, hn::Set(di, 1)));
  VF nz = hn::GatherIndex(df, s.normals, hn::Add(tri3, hn::Set(di, 2)));
  const VF n_dot_view = hn::MulAdd(nx, vx, hn::MulAdd(ny, vy, hn::Mul(nz, vz)));
  const MF back = hn::Gt(n_dot_view, hn::Zero(df));
  nx = hn::IfThenElse(back, hn::Neg(nx), nx);
  ny = hn::IfThenElse(back, hn::Neg(ny), ny);
  nz = hn::IfThenElse(back, hn::Neg(nz), nz);
  const VF cos_view = hn::Max(hn::Set(df, kMinViewCosine), hn::Abs(n_dot_view));
  const VF footprint_m = hn::Div(hn::Mul(z, hn::Set(df, 1.0f / s.fx)), cos_view);

  // Texture: coordinates in the triangle's plane, two layers.
  const VI code = hn::GatherIndex(di, s.shading_codes, tri);
  const VI plane = hn::And(code, hn::Set(di, 3));
  const VI material = hn::ShiftRight<2>(code);
  const VF offset_u = hn::IfThenElse(hn::RebindMask(df, hn::Eq(plane, hn::Set(di, 1))), oy, ox);
  const VF offset_v = hn::IfThenElse(hn::RebindMask(df, hn::Eq(plane, hn::Zero(di))), oy, oz);
  auto layer = [&](const TextureLayer& tex) {
    const VF k = hn::Set(df, tex.texels_per_m);
    return sampleTexture(df, tex, hn::MulAdd(offset_u, k, byPlane(df, plane, tex.origin_u)),
                         hn::MulAdd(offset_v, k, byPlane(df, plane, tex.origin_v)), hn::Mul(footprint_m, k));
  };
  using T = SurfaceTexture;
  const VF mix = hn::MulAdd(hn::Set(df, T::kFineWeight), layer(s.fine),
                            hn::Mul(hn::Set(df, 1.0f - T::kFineWeight), layer(s.coarse)));
  const VF value = hn::Min(
      hn::Set(df, 1.0f),
      hn::Max(hn::Zero(df), hn::MulAdd(hn::Set(df, T::kContrast), hn::Sub(mix, hn::Set(df, 0.5f)), hn::Set(df, 0.5f))));
  const VF shade = hn::MulAdd(hn::Set(df, 1.0f - T::kMinShade), value, hn::Set(df, T::kMinShade));

  // Light: rig lamp (spot, inverse square, attenuated on its way) and sunlight from above.
  VF light_scale = hn::Zero(df), lamp_distance = hn::Zero(df), sun_scale = hn::Zero(df), below = hn::Zero(df);
  if (s.rig_light) {
    const VF lx = hn::Sub(hn::Set(df, s.lamp[0]), ox), ly = hn::Sub(hn::Set(df, s.lamp[1]), oy);
    const VF lz = hn::Sub(hn::Set(df, s.lamp[2]), oz);
    lamp_distance = hn::Sqrt(hn::MulAdd(lx, lx, hn::MulAdd(ly, ly, hn::Mul(lz, lz))));
    const VF inverse_d = hn::Div(hn::Set(df, 1.0f), lamp_distance);
    const VF incidence = hn::Max(hn::Zero(df), hn::Mul(hn::MulAdd(nx, lx, hn::MulAdd(ny, ly, hn::Mul(nz, lz))), inverse_d));
    const VF along_axis = hn::MulAdd(hn::Set(df, s.lamp_axis[0]), lx,
                                     hn::MulAdd(hn::Set(df, s.lamp_axis[1]), ly, hn::Mul(hn::Set(df, s.lamp_axis[2]), lz)));
    const VF axis_cos = hn::Max(hn::Zero(df), hn::Neg(hn::Mul(along_axis, inverse_d)));
    light_scale = hn::Mul(hn::Mul(hn::Set(df, s.rig_intensity), hn::Mul(axis_cos, axis_cos)),
                          hn::Mul(incidence, hn::Mul(inverse_d, inverse_d)));
  }
  if (s.sun) {
    below = hn::Max(hn::Zero(df), hn::Sub(hn::Set(df, s.surface_above_camera_m), oz));
    sun_scale = hn::MulAdd(hn::Set(df, 1.0f - s.ambient), hn::Max(hn::Zero(df), nz), hn::Set(df, s.ambient));
  }
  VF radiance[3];
  for (int c = 0; c < 3; ++c) {
    const VF beta = hn::Set(df, s.beta[c]);
    VF irradiance = hn::Zero(df);
    if (s.rig_light) irradiance = hn::Mul(light_scale, fastExp(df, hn::Neg(hn::Mul(beta, lamp_distance))));
    if (s.sun) {
      const VF sun = hn::Mul(hn::Set(df, s.sun_irradiance[c]),
                             fastExp(df, hn::Neg(hn::Mul(hn::Set(df, s.downwelling[c]), below))));
      irradiance = hn::MulAdd(sun, sun_scale, irradiance);
    }
    const VF albedo = hn::Mul(hn::GatherIndex(df, s.albedo[c], material), shade);
    const VF transmission = fastExp(df, hn::Neg(hn::Mul(beta, range)));
    const VF backscatter = hn::Set(df, s.backscatter[c]);
    const VF lit = hn::Mul(hn::Mul(albedo, irradiance), transmission);
    radiance[c] = hn::IfThenElse(valid, hn::MulAdd(backscatter, hn::Sub(hn::Set(df, 1.0f), transmission), lit),
                                 backscatter);
  }
  hn::StoreInterleaved3(radiance[0], radiance[1], radiance[2], df, out);
}

void ShadeRadianceRowImpl(const RadianceSetup& s, int y, const int32_t* ids, const float* depth, float* out_bgr) {
  const DF df;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const float ray_y = (static_cast<float>(y) - s.cy) / s.fy;
  int x = 0;
  for (; x + lanes <= s.width; x += lanes) shadePixels(s, x, ray_y, ids + x, depth + x, out_bgr + 3 * x);
  if (x == s.width) return;
  // The last partial vector through padded copies (padding lanes have no surface).
  HWY_ALIGN int32_t id_tail[HWY_MAX_BYTES / sizeof(float)];
  HWY_ALIGN float depth_tail[HWY_MAX_BYTES / sizeof(float)];
  HWY_ALIGN float out_tail[3 * HWY_MAX_BYTES / sizeof(float)];
  const int rest = s.width - x;
  for (int i = 0; i < lanes; ++i) {
    id_tail[i] = i < rest ? ids[x + i] : -1;
    depth_tail[i] = i < rest ? depth[x + i] : 1.0f;
  }
  shadePixels(s, x, ray_y, id_tail, depth_tail, out_tail);
  std::memcpy(out_bgr + 3 * x, out_tail, sizeof(float) * 3 * static_cast<size_t>(rest));
}

// sensorNoise() of samples i (the same operations, lane by lane).
HWY_INLINE VF sensorNoiseLanes(DF df, uint64_t key, VU i) {
  const DU du;
  const DI di;
  VU h = hn::Mul(hn::Xor(i, hn::Set(du, static_cast<uint32_t>(key))), hn::Set(du, kNoiseMul0));
  h = hn::Xor(h, hn::Set(du, static_cast<uint32_t>(key >> 32)));
  h = hn::Xor(h, hn::ShiftRight<16>(h));
  h = hn::Mul(h, hn::Set(du, kNoiseMul1));
  h = hn::Xor(h, hn::ShiftRight<13>(h));
  h = hn::Mul(h, hn::Set(du, kNoiseMul2));
  h = hn::Xor(h, hn::ShiftRight<16>(h));
  const VU byte = hn::Set(du, 0xFFu);
  const VU sum = hn::Add(hn::Add(hn::And(h, byte), hn::And(hn::ShiftRight<8>(h), byte)),
                         hn::Add(hn::And(hn::ShiftRight<16>(h), byte), hn::ShiftRight<24>(h)));
  return hn::Mul(hn::Sub(hn::ConvertTo(df, hn::BitCast(di, sum)), hn::Set(df, kNoiseMean)), hn::Set(df, kNoiseScale));
}

// Samples [k, k + lanes) of exposeRow.
HWY_INLINE void exposeSamples(const float* in, int k, uint32_t first, float gain, float noise_sigma, uint64_t key,
                              const float* gamma_table, int gamma_levels, uint8_t* out) {
  const DF df;
  const DI di;
  const DU du;
  const hn::Rebind<uint8_t, DI> d8;
  const VF v = hn::Min(hn::Set(df, 1.0f), hn::Max(hn::Zero(df), hn::Mul(hn::LoadU(df, in + k), hn::Set(df, gain))));
  const VI j = hn::ConvertTo(di, hn::MulAdd(v, hn::Set(df, static_cast<float>(gamma_levels)), hn::Set(df, 0.5f)));
  const VF level = hn::GatherIndex(df, gamma_table, j);
  const VU i = hn::Add(hn::Iota(du, static_cast<uint32_t>(k)), hn::Set(du, first));
  const VF noisy = hn::MulAdd(hn::Set(df, noise_sigma), sensorNoiseLanes(df, key, i), level);
  const VF clipped = hn::Min(hn::Set(df, 255.0f), hn::Max(hn::Zero(df), hn::Add(noisy, hn::Set(df, 0.5f))));
  hn::StoreU(hn::DemoteTo(d8, hn::ConvertTo(di, clipped)), d8, out + k);
}

void ExposeRowImpl(const float* in, int count, uint32_t first, float gain, float noise_sigma, uint64_t key,
                   const float* gamma_table, int gamma_levels, uint8_t* out) {
  const DF df;
  const int lanes = static_cast<int>(hn::Lanes(df));
  if (count >= lanes) {
    // The last vector is shifted back to end at the last sample (a sample's value depends only on
    // its index, so the overlap writes the same bytes twice).
    for (int k = 0; k < count; k += lanes) {
      exposeSamples(in, std::min(k, count - lanes), first, gain, noise_sigma, key, gamma_table, gamma_levels, out);
    }
    return;
  }
  HWY_ALIGN float in_pad[HWY_MAX_BYTES / sizeof(float)] = {};
  HWY_ALIGN uint8_t out_pad[HWY_MAX_BYTES / sizeof(float)];
  std::memcpy(in_pad, in, sizeof(float) * static_cast<size_t>(count));
  exposeSamples(in_pad, 0, first, gain, noise_sigma, key, gamma_table, gamma_levels, out_pad);
  std::memcpy(out, out_pad, static_cast<size_t>(count));
}

}  // namespace HWY_NAMESPACE
}  // namespace cenote::sim::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::sim::detail {

HWY_EXPORT(ShadeRadianceRowImpl);
HWY_EXPORT(ExposeRowImpl);

float sensorNoise(uint64_t key, uint32_t i) {
  uint32_t h = (i ^ static_cast<uint32_t>(key)) * kNoiseMul0;
  h ^= static_cast<uint32_t>(key >> 32);
  h ^= h >> 16;
  h *= kNoiseMul1;
  h ^= h >> 13;
  h *= kNoiseMul2;
  h ^= h >> 16;
  const uint32_t sum = (h & 0xFF) + ((h >> 8) & 0xFF) + ((h >> 16) & 0xFF) + (h >> 24);
  return (static_cast<float>(sum) - kNoiseMean) * kNoiseScale;
}

void exposeRow(const float* in, int count, uint32_t first, float gain, float noise_sigma, uint64_t key,
               const float* gamma_table, int gamma_levels, uint8_t* out) {
  HWY_DYNAMIC_DISPATCH(ExposeRowImpl)(in, count, first, gain, noise_sigma, key, gamma_table, gamma_levels, out);
}

void shadeRadianceRow(const RadianceSetup& setup, int y, const int32_t* ids, const float* depth, float* out_bgr) {
  HWY_DYNAMIC_DISPATCH(ShadeRadianceRowImpl)(setup, y, ids, depth, out_bgr);
}

}  // namespace cenote::sim::detail
#endif  // HWY_ONCE
