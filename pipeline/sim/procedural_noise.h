// procedural_noise.h: seeded, deterministic noise for the simulator's geometry and texture.
//   hash64()          counter-based hash: the same inputs give the same bits on every machine
//   valueNoise3()     smooth value noise in [-1, 1], unit lattice spacing
//   fbm3()            fractal sum of octaves of valueNoise3, roughly in [-1, 1]
//   NoiseTexture      a tileable square fBm texture (mean 0.5, sd 0.2, in [0, 1]) with mips, sampled trilinearly;
//                     each texel stores its 2 x 2 neighbourhood, so a bilinear tap is one 32-bit load
//                     (or one SIMD gather lane: image_formation_kernels.cpp reads quads() directly)
// Units: the caller's (noise is defined on a unit lattice; scale the input).
// Threads: pure functions; a NoiseTexture is immutable after construction and may be shared (its
// constructor fills the texels on OpenMP threads, the same bits on any thread count).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace cenote::pipeline {

// SplitMix64-style finaliser over the combined inputs.
inline uint64_t hash64(uint64_t a, uint64_t b = 0, uint64_t c = 0, uint64_t d = 0) {
  uint64_t x = a * 0x9E3779B97F4A7C15ULL ^ (b + 0x632BE59BD9B4E019ULL) * 0xBF58476D1CE4E5B9ULL;
  x ^= (c + 0x8CB92BA72F3D8DD7ULL) * 0x94D049BB133111EBULL;
  x ^= (d + 0xD6E8FEB86659FD93ULL) * 0x9E3779B97F4A7C15ULL;
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ULL;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBULL;
  x ^= x >> 31;
  return x;
}

// Uniform in [0, 1) from a hash.
inline double hashToUnit(uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

// Smooth (quintic-interpolated) value noise in [-1, 1].
double valueNoise3(double x, double y, double z, uint64_t seed);

// Sum over `octaves` of valueNoise3 at doubling frequency and `gain`-decaying amplitude,
// normalised by the total amplitude.
double fbm3(double x, double y, double z, uint64_t seed, int octaves, double gain = 0.5);

class NoiseTexture {
 public:
  // size: a power of two >= 8 (texels per side); periods of the octaves are size, size/2, ... 4 texels.
  NoiseTexture(int size, uint64_t seed);

  int size() const { return size_; }
  int levels() const { return static_cast<int>(level_offsets_.size()); }

  // Trilinear sample at texel coordinates (u, v) of level 0 (wrapping), footprint_texels the pixel's
  // size in level-0 texels (chooses and blends the mip levels; <= 1 samples level 0).
  // Inline: the simulator calls it several times per pixel.
  float sample(float u, float v, float footprint_texels) const;

  // Texel (x, y) of level k (n = size >> k texels wide) is quads()[levelOffsets()[k] + y * n + x]:
  // bits 0-7 texel (x, y), 8-15 (x + 1, y), 16-23 (x, y + 1), 24-31 (x + 1, y + 1), wrapping;
  // 8-bit values of value * 255.
  const uint32_t* quads() const { return quads_.data(); }
  const int32_t* levelOffsets() const { return level_offsets_.data(); }
  int sizeLog2() const { return size_log2_; }

 private:
  float bilinear(int level, float u, float v) const;

  // 2^-k for k in [0, 31]: exact, and no division per sample.
  static constexpr float kInversePowersOfTwo[32] = {
      1.0f,        0x1p-1f,  0x1p-2f,  0x1p-3f,  0x1p-4f,  0x1p-5f,  0x1p-6f,  0x1p-7f,  0x1p-8f,  0x1p-9f,  0x1p-10f,
      0x1p-11f,    0x1p-12f, 0x1p-13f, 0x1p-14f, 0x1p-15f, 0x1p-16f, 0x1p-17f, 0x1p-18f, 0x1p-19f, 0x1p-20f, 0x1p-21f,
      0x1p-22f,    0x1p-23f, 0x1p-24f, 0x1p-25f, 0x1p-26f, 0x1p-27f, 0x1p-28f, 0x1p-29f, 0x1p-30f, 0x1p-31f};

  int size_;
  int size_log2_ = 0;
  std::vector<uint32_t> quads_;         // all levels, finest first, row-major
  std::vector<int32_t> level_offsets_;  // first texel of each level in quads_
};

namespace detail {

// log2 of x > 0 to ~1e-2: exponent plus a quadratic in the mantissa m in [1, 2) that is exact at
// m = 1, 1.5 and 2 (so continuous across powers of two).
inline float fastLog2(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  const float exponent = static_cast<float>(static_cast<int>(bits >> 23) - 127);
  bits = (bits & 0x007FFFFF) | 0x3F800000;
  float m;
  std::memcpy(&m, &bits, sizeof(m));
  return exponent + (-0.33985f * m + 2.01955f) * m - 1.6797f;
}

}  // namespace detail

inline float NoiseTexture::bilinear(int level, float u, float v) const {
  const int n = size_ >> level;
  const float scale = kInversePowersOfTwo[level];
  // Texel centres of level k sit at (i + 0.5) * 2^k - 0.5 in level-0 coordinates.
  const float x = (u + 0.5f) * scale - 0.5f, y = (v + 0.5f) * scale - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  const int mask = n - 1;
  const int x0 = static_cast<int>(fx) & mask, y0 = static_cast<int>(fy) & mask;
  const uint32_t q = quads_[static_cast<size_t>(level_offsets_[level]) + static_cast<size_t>(y0 * n + x0)];
  const auto t00 = static_cast<float>(q & 0xFF), t10 = static_cast<float>((q >> 8) & 0xFF);
  const auto t01 = static_cast<float>((q >> 16) & 0xFF), t11 = static_cast<float>(q >> 24);
  const float a = t00 + (t10 - t00) * tx;
  const float b = t01 + (t11 - t01) * tx;
  return (a + (b - a) * ty) * (1.0f / 255.0f);
}

inline float NoiseTexture::sample(float u, float v, float footprint_texels) const {
  // Keep texture coordinates small so that float keeps sub-texel precision far from the origin.
  // (u * inverse_size is u / size to the bit: size is a power of two.)
  const float period = static_cast<float>(size_);
  const float inverse_period = kInversePowersOfTwo[size_log2_];
  u -= period * std::floor(u * inverse_period);
  v -= period * std::floor(v * inverse_period);
  if (footprint_texels <= 1.0f) return bilinear(0, u, v);
  const float lod = std::min(detail::fastLog2(footprint_texels), static_cast<float>(levels() - 1) - 1e-3f);
  const int level = static_cast<int>(lod);
  const float t = lod - static_cast<float>(level);
  const float a = bilinear(level, u, v);
  return a + (bilinear(level + 1, u, v) - a) * t;
}

}  // namespace cenote::pipeline
