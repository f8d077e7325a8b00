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
#include <vector>

namespace cenote::sim {

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
  // size in level-0 texels (chooses and blends the mip levels; <= 1 samples level 0). The scalar
  // reference: the simulator's shader samples 16 pixels at a time from quads() itself.
  float sample(float u, float v, float footprint_texels) const;

  // Texel (x, y) of level k (n = size >> k texels wide) is quads()[levelOffsets()[k] + y * n + x]:
  // bits 0-7 texel (x, y), 8-15 (x + 1, y), 16-23 (x, y + 1), 24-31 (x + 1, y + 1), wrapping;
  // 8-bit values of value * 255.
  const uint32_t* quads() const { return quads_.data(); }
  const int32_t* levelOffsets() const { return level_offsets_.data(); }
  int sizeLog2() const { return size_log2_; }

 private:
  float bilinear(int level, float u, float v) const;

  int size_;
  int size_log2_ = 0;
  std::vector<uint32_t> quads_;         // all levels, finest first, row-major
  std::vector<int32_t> level_offsets_;  // first texel of each level in quads_
};

namespace detail {

// log2(x) for x > 0 to ~1e-2 (what picks a mip level): the exponent plus kLog2Poly[0] m^2 +
// kLog2Poly[1] m + kLog2Poly[2] of the mantissa m in [1, 2), exact at m = 1, 1.5 and 2 (so
// continuous across powers of two). NoiseTexture::sample and the SIMD shader both use it.
inline constexpr float kLog2Poly[3] = {-0.33985f, 2.01955f, -1.6797f};

}  // namespace detail

}  // namespace cenote::sim
