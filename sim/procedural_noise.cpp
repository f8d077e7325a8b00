#include "sim/procedural_noise.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/error.h"

namespace cenote::sim {
namespace {

inline double quintic(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

inline double lattice(int64_t x, int64_t y, int64_t z, uint64_t seed) {
  return hashToUnit(hash64(static_cast<uint64_t>(x), static_cast<uint64_t>(y), static_cast<uint64_t>(z), seed)) * 2.0 - 1.0;
}

// The lattice of one tileable 2D value noise: period x period values, computed once per octave
// (four hashes per texel and octave were most of building a texture). period: a power of two.
class TiledLattice {
 public:
  TiledLattice(int period, uint64_t seed) : period_(period), values_(static_cast<size_t>(period) * period) {
    for (int j = 0; j < period; ++j) {
      for (int i = 0; i < period; ++i) values_[static_cast<size_t>(j) * period + i] = lattice(i, j, period, seed);
    }
  }
  // The value at lattice point (i, j), wrapping (i & (period - 1) is i mod period, negative i too).
  double at(int i, int j) const {
    return values_[static_cast<size_t>(j & (period_ - 1)) * period_ + static_cast<size_t>(i & (period_ - 1))];
  }

 private:
  int period_;
  std::vector<double> values_;
};

// Tileable 2D value noise on `lattice` (quintic interpolation between lattice points).
double tiledNoise2(double x, double y, const TiledLattice& lattice) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  const double tx = quintic(x - fx), ty = quintic(y - fy);
  const double a = lattice.at(ix, iy) + (lattice.at(ix + 1, iy) - lattice.at(ix, iy)) * tx;
  const double b = lattice.at(ix, iy + 1) + (lattice.at(ix + 1, iy + 1) - lattice.at(ix, iy + 1)) * tx;
  return a + (b - a) * ty;
}

// detail::kLog2Poly's approximation of log2(x), x > 0.
float fastLog2(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  const float exponent = static_cast<float>(static_cast<int>(bits >> 23) - 127);
  bits = (bits & 0x007FFFFF) | 0x3F800000;
  float m;
  std::memcpy(&m, &bits, sizeof(m));
  using detail::kLog2Poly;
  return exponent + (kLog2Poly[0] * m + kLog2Poly[1]) * m + kLog2Poly[2];
}

}  // namespace

double valueNoise3(double x, double y, double z, uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const auto ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy), iz = static_cast<int64_t>(fz);
  const double tx = quintic(x - fx), ty = quintic(y - fy), tz = quintic(z - fz);
  double c[2][2];
  for (int j = 0; j < 2; ++j) {
    for (int k = 0; k < 2; ++k) {
      const double a = lattice(ix, iy + j, iz + k, seed);
      const double b = lattice(ix + 1, iy + j, iz + k, seed);
      c[j][k] = a + (b - a) * tx;
    }
  }
  const double lo = c[0][0] + (c[1][0] - c[0][0]) * ty;
  const double hi = c[0][1] + (c[1][1] - c[0][1]) * ty;
  return lo + (hi - lo) * tz;
}

double fbm3(double x, double y, double z, uint64_t seed, int octaves, double gain) {
  double sum = 0.0, amplitude = 1.0, total = 0.0, frequency = 1.0;
  for (int o = 0; o < octaves; ++o) {
    // Each octave has its own lattice (seed) and an offset so that lattice points do not line up.
    sum += amplitude * valueNoise3(x * frequency + 17.31 * o, y * frequency - 9.17 * o, z * frequency + 3.71 * o,
                                   seed + 0x1000 * static_cast<uint64_t>(o + 1));
    total += amplitude;
    amplitude *= gain;
    frequency *= 2.0;
  }
  return total > 0.0 ? sum / total : 0.0;
}

NoiseTexture::NoiseTexture(int size, uint64_t seed) : size_(size) {
  if (size < 8 || (size & (size - 1)) != 0) {
    throw Error("NoiseTexture: size " + std::to_string(size) + " must be a power of two >= 8");
  }
  while ((1 << size_log2_) < size) ++size_log2_;
  // Level 0: octaves of period size, size/2, ..., 4 texels, amplitude falling slower than 1/f so
  // that fine detail (what stereo matches on) stays strong.
  std::vector<TiledLattice> octaves;
  for (int cells = 1, o = 0; size / cells >= 4; cells *= 2, ++o) octaves.emplace_back(cells, seed + 31 * o);
  std::vector<float> base(static_cast<size_t>(size) * size);
#pragma omp parallel for schedule(static)  // each texel on its own: the same texture on any thread count
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      double sum = 0.0, amplitude = 1.0;
      for (int cells = 1, o = 0; size / cells >= 4; cells *= 2, ++o) {
        const double scale = static_cast<double>(cells) / size;
        sum += amplitude * tiledNoise2(x * scale, y * scale, octaves[o]);
        amplitude *= 0.72;
      }
      base[static_cast<size_t>(y) * size + x] = static_cast<float>(sum);
    }
  }
  // Normalise to mean 0.5 and standard deviation kContrast, clipped to [0, 1]: a fixed contrast
  // whatever the number of octaves. Mips are box-filtered in float, then stored as 8-bit texels.
  constexpr double kContrast = 0.2;
  double mean = 0.0, square = 0.0;
  for (float v : base) {
    mean += v;
    square += static_cast<double>(v) * v;
  }
  mean /= static_cast<double>(base.size());
  const double sigma = std::sqrt(std::max(1e-12, square / static_cast<double>(base.size()) - mean * mean));
  for (float& v : base) v = static_cast<float>(std::clamp(0.5 + kContrast * (v - mean) / sigma, 0.0, 1.0));
  auto store = [this](const std::vector<float>& level, int n) {
    level_offsets_.push_back(static_cast<int32_t>(quads_.size()));
    auto at = [&](int x, int y) {
      return static_cast<uint32_t>(std::lround(255.0f * level[static_cast<size_t>(y & (n - 1)) * n + (x & (n - 1))]));
    };
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        quads_.push_back(at(x, y) | at(x + 1, y) << 8 | at(x, y + 1) << 16 | at(x + 1, y + 1) << 24);
      }
    }
  };
  store(base, size);
  std::vector<float> up = std::move(base);
  for (int n = size / 2; n >= 1; n /= 2) {
    std::vector<float> down(static_cast<size_t>(n) * n);
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const size_t i = static_cast<size_t>(2 * y) * (2 * n) + 2 * x;
        down[static_cast<size_t>(y) * n + x] = 0.25f * (up[i] + up[i + 1] + up[i + 2 * n] + up[i + 2 * n + 1]);
      }
    }
    store(down, n);
    up = std::move(down);
  }
}

float NoiseTexture::bilinear(int level, float u, float v) const {
  const int n = size_ >> level;
  const float scale = std::ldexp(1.0f, -level);
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

float NoiseTexture::sample(float u, float v, float footprint_texels) const {
  // Keep texture coordinates small so that float keeps sub-texel precision far from the origin.
  // (u * inverse_period is u / period to the bit: the period is a power of two.)
  const auto period = static_cast<float>(size_);
  const float inverse_period = std::ldexp(1.0f, -size_log2_);
  u -= period * std::floor(u * inverse_period);
  v -= period * std::floor(v * inverse_period);
  if (footprint_texels <= 1.0f) return bilinear(0, u, v);
  const float lod = std::min(fastLog2(footprint_texels), static_cast<float>(levels() - 1) - 1e-3f);
  const int level = static_cast<int>(lod);
  const float t = lod - static_cast<float>(level);
  const float a = bilinear(level, u, v);
  return a + (bilinear(level + 1, u, v) - a) * t;
}

}  // namespace cenote::sim
