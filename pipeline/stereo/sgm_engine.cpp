// sgm_engine.cpp: Highway implementation of sgm_engine.h, compiled once per instruction set.
//
// Memory layout (uint16, Dp = disparities padded to the vector width):
//   cost row        [x][Dp]                 matching cost of the current row
//   path rows       [(x + 1) * pixel_stride + N + d]  for x in [-1, W]: pixels -1 and W hold zero
//                   costs ("no predecessor", so a path starts with L = C), and every pixel has N
//                   sentinel lanes before and after its Dp values, read by the d - 1 / d + 1 loads.
// Path recurrence (Hirschmueller 2008), for one direction r:
//   L(p, d) = C(p, d) + min(L(p-r, d), L(p-r, d+-1) + P1, min_k L(p-r, k) + P2) - min_k L(p-r, k)
// which stays within [0, max_cost + P2]; the sum over all paths is validated to fit 16 bits.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "pipeline/stereo/sgm_engine.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "pipeline/stereo/sgm_engine.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::pipeline::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DU16 = hn::ScalableTag<uint16_t>;
using VU16 = hn::Vec<DU16>;

constexpr uint16_t kNoCost = 0xFFFF;  // masks lanes out of the winner search

// Smallest lane of a uint16 vector: halve to 128 bits, then one PHMINPOSUW on x86 (Highway's
// generic MinOfLanes costs several shuffles per halving and dominated the profile).
template <class D>
HWY_INLINE uint16_t minLane(D d, hn::Vec<D> v) {
#if HWY_TARGET == HWY_SCALAR
  return hn::GetLane(v);
#else
  if constexpr (hn::MaxLanes(D()) * sizeof(uint16_t) > 16) {
    const hn::Half<D> dh;
    return minLane(dh, hn::Min(hn::LowerHalf(dh, v), hn::UpperHalf(dh, v)));
  } else {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_SSE4
    if constexpr (hn::MaxLanes(D()) == 8) {
      return static_cast<uint16_t>(_mm_cvtsi128_si32(_mm_minpos_epu16(v.raw)) & 0xFFFF);
    }
#endif
    return hn::GetLane(hn::MinOfLanes(d, v));
  }
#endif
}

// Lane shifts across a whole vector: [prev[N-1], cur[0..N-2]] (the d-1 neighbours of `cur`) and
// [cur[1..N-1], next[0]] (the d+1 neighbours). The along-row path needs them in registers: the
// previous pixel's path costs were stored just before, and an unaligned reload of them would miss
// store-to-load forwarding on every vector (it dominated the profile).
HWY_INLINE VU16 shiftInPrevious(VU16 prev, VU16 cur) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  alignas(64) static constexpr uint16_t kIndex[32] = {63, 0,  1,  2,  3,  4,  5,  6,  7,  8,  9,
                                                      10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20,
                                                      21, 22, 23, 24, 25, 26, 27, 28, 29, 30};
  return VU16{_mm512_permutex2var_epi16(cur.raw, _mm512_load_si512(kIndex), prev.raw)};
#elif HWY_ARCH_X86 && HWY_TARGET == HWY_AVX2
  return VU16{_mm256_alignr_epi8(cur.raw, _mm256_permute2x128_si256(prev.raw, cur.raw, 0x21), 14)};
#elif HWY_ARCH_X86 && HWY_TARGET <= HWY_SSSE3 && HWY_TARGET >= HWY_SSE4
  return VU16{_mm_alignr_epi8(cur.raw, prev.raw, 14)};
#else
  const DU16 d;
  HWY_ALIGN uint16_t lanes[2 * hn::MaxLanes(DU16())];
  const size_t N = hn::Lanes(d);
  hn::Store(prev, d, lanes);
  hn::Store(cur, d, lanes + N);
  return hn::LoadU(d, lanes + N - 1);
#endif
}

HWY_INLINE VU16 shiftInNext(VU16 cur, VU16 next) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  alignas(64) static constexpr uint16_t kIndex[32] = {1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11,
                                                      12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22,
                                                      23, 24, 25, 26, 27, 28, 29, 30, 31, 32};
  return VU16{_mm512_permutex2var_epi16(cur.raw, _mm512_load_si512(kIndex), next.raw)};
#elif HWY_ARCH_X86 && HWY_TARGET == HWY_AVX2
  return VU16{_mm256_alignr_epi8(_mm256_permute2x128_si256(cur.raw, next.raw, 0x21), cur.raw, 2)};
#elif HWY_ARCH_X86 && HWY_TARGET <= HWY_SSSE3 && HWY_TARGET >= HWY_SSE4
  return VU16{_mm_alignr_epi8(next.raw, cur.raw, 2)};
#else
  const DU16 d;
  HWY_ALIGN uint16_t lanes[2 * hn::MaxLanes(DU16())];
  const size_t N = hn::Lanes(d);
  hn::Store(cur, d, lanes);
  hn::Store(next, d, lanes + N);
  return hn::LoadU(d, lanes + 1);
#endif
}

// Directions of one pass: index 0 = along the row (from x - dx), 1 = from the previous row at x,
// 2 = previous row at x - dx, 3 = previous row at x + dx.
constexpr int kPrevRowPaths = 3;

// Carves the strip's buffers out of the workspace.
struct StripBuffers {
  int width = 0;
  int lanes = 0;
  int padded = 0;         // Dp
  int pixel_stride = 0;   // Dp + 2 * lanes
  uint16_t* ring = nullptr;       // window rows of absolute differences (SAD)
  uint16_t* column_sum = nullptr; // SAD column sums over the window rows
  uint16_t* running = nullptr;    // SAD running horizontal sum, Dp
  uint16_t* cost = nullptr;
  uint16_t* path_prev[kPrevRowPaths] = {};
  uint16_t* path_cur[kPrevRowPaths] = {};
  uint16_t* min_prev[kPrevRowPaths] = {};  // W + 2 each
  uint16_t* min_cur[kPrevRowPaths] = {};
  uint16_t* along[2] = {};        // the along-row path: previous and current pixel
  uint16_t* sums = nullptr;       // [x][Dp] path sums of the current row
  uint16_t* right_min = nullptr;  // LR check: best sum per right pixel, stored reversed
  uint16_t* right_arg = nullptr;
  int16_t* winner = nullptr;      // W, integer winner per pixel of the row (-1 = invalid)
  uint8_t* right_reversed = nullptr;      // right image row, reversed and padded
  uint32_t* census_reversed = nullptr;    // right census row, reversed and padded
  int reversed_length = 0;

  uint16_t* pathPixel(uint16_t* row, int x) const {
    return row + static_cast<std::ptrdiff_t>(x + 1) * pixel_stride + lanes;
  }
};

std::size_t alignUp(std::size_t n, std::size_t a) { return (n + a - 1) / a * a; }

StripBuffers carveBuffers(const SgmParams& p, SgmWorkspace& ws) {
  const DU16 d;
  StripBuffers b;
  b.width = p.width;
  b.lanes = static_cast<int>(hn::Lanes(d));
  b.padded = static_cast<int>(alignUp(p.num_disparities, b.lanes));
  b.pixel_stride = b.padded + 2 * b.lanes;
  const std::size_t W = p.width, Dp = b.padded;
  const std::size_t row = alignUp(W * Dp, 64);
  const std::size_t path_row = alignUp((W + 2) * b.pixel_stride, 64);
  const std::size_t min_row = alignUp(W + 2, 64);
  b.reversed_length = static_cast<int>(alignUp(W + p.min_disparity + Dp + 2 * b.lanes, 64));
  const std::size_t rev = b.reversed_length;
  const int ring_rows = p.census ? 0 : p.window;
  const std::size_t total = row * (ring_rows + 3) + alignUp(Dp, 64) * 2 + path_row * 2 * kPrevRowPaths +
                            min_row * 2 * kPrevRowPaths + alignUp(b.pixel_stride, 64) * 2 +
                            rev * 2 + alignUp(W, 64) + rev / 2 + 64 + rev * 2 + 64;
  if (ws.buffer_elements < total) {
    ws.buffer = hwy::AllocateAligned<uint16_t>(total);
    ws.buffer_elements = total;
  }
  uint16_t* next = ws.buffer.get();
  auto take = [&next](std::size_t n) {
    uint16_t* out = next;
    next += alignUp(n, 64);
    return out;
  };
  b.ring = take(row * ring_rows);
  b.column_sum = take(row);
  b.cost = take(row);
  b.running = take(Dp);
  b.sums = take(row);
  for (int i = 0; i < kPrevRowPaths; ++i) {
    b.path_prev[i] = take(path_row);
    b.path_cur[i] = take(path_row);
    b.min_prev[i] = take(min_row);
    b.min_cur[i] = take(min_row);
  }
  b.along[0] = take(b.pixel_stride);
  b.along[1] = take(b.pixel_stride);
  b.right_min = take(rev);
  b.right_arg = take(rev);
  b.winner = reinterpret_cast<int16_t*>(take(W));
  b.right_reversed = reinterpret_cast<uint8_t*>(take(rev / 2 + 32));
  b.census_reversed = reinterpret_cast<uint32_t*>(take(rev * 2 + 32));
  return b;
}

// ---------------------------------------------------------------------------------------------
// Matching cost of one row: cost[x][k] for disparity min_disparity + k.

// Right image row y reversed: reversed[j] = right[W - 1 - j], so that the pixels x - k of one
// left pixel x are contiguous in k. Past the left image border the row is replicated (those
// disparities are masked out of the cost later).
template <typename T>
void reverseRow(const T* row, int width, int length, T* reversed) {
  for (int j = 0; j < width; ++j) reversed[j] = row[width - 1 - j];
  for (int j = width; j < length; ++j) reversed[j] = row[0];
}

// Absolute differences of left row y against the reversed right row, for every x and k.
void absDiffRow(const SgmParams& p, const StripBuffers& b, const uint8_t* left_row,
                const uint8_t* right_reversed, uint16_t* out) {
  const DU16 d;
  const hn::Rebind<uint8_t, DU16> d8;
  const int N = b.lanes, Dp = b.padded, W = p.width;
  for (int x = 0; x < W; ++x) {
    const VU16 l = hn::Set(d, left_row[x]);
    const uint8_t* r = right_reversed + (W - 1 - x + p.min_disparity);
    uint16_t* o = out + static_cast<std::ptrdiff_t>(x) * Dp;
    for (int k = 0; k < Dp; k += N) {
      const VU16 rv = hn::PromoteTo(d, hn::LoadU(d8, r + k));
      hn::Store(hn::Sub(hn::Max(l, rv), hn::Min(l, rv)), d, o + k);
    }
  }
}

struct CostRowState {
  int current_row = std::numeric_limits<int>::min();
};

int clampRow(int y, int height) { return std::clamp(y, 0, height - 1); }
int ringSlot(int y, int window) { return ((y % window) + window) % window; }

// Absolute differences of image row `y` (clamped) into the ring slot of y.
void loadDiffRow(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y,
                 uint16_t* out) {
  const int yc = clampRow(y, p.height);
  reverseRow(im.right + yc * im.image_stride, p.width, b.reversed_length, b.right_reversed);
  absDiffRow(p, b, im.left + yc * im.image_stride, b.right_reversed, out);
}

// Column sums over rows [y - r, y + r] for the first row of a pass.
void initColumnSums(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y) {
  const DU16 d;
  const int r = p.window / 2;
  const std::size_t n = static_cast<std::size_t>(p.width) * b.padded;
  std::fill(b.column_sum, b.column_sum + n, 0);
  for (int yy = y - r; yy <= y + r; ++yy) {
    uint16_t* slot = b.ring + static_cast<std::size_t>(ringSlot(yy, p.window)) * n;
    loadDiffRow(p, im, b, yy, slot);
    for (std::size_t i = 0; i < n; i += b.lanes) {
      hn::Store(hn::Add(hn::Load(d, b.column_sum + i), hn::Load(d, slot + i)), d, b.column_sum + i);
    }
  }
}

// Slides the column sums one row (dy = +1 down, -1 up): the entering row replaces the leaving
// one, which sits in the same ring slot since they are `window` rows apart.
void slideColumnSums(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y,
                     int dy) {
  const DU16 d;
  const int r = p.window / 2;
  const int entering = y + dy * r;
  const std::size_t n = static_cast<std::size_t>(p.width) * b.padded;
  uint16_t* slot = b.ring + static_cast<std::size_t>(ringSlot(entering, p.window)) * n;
  // The entering row's differences go to `cost` first (free at this point), then into the slot.
  loadDiffRow(p, im, b, entering, b.cost);
  for (std::size_t i = 0; i < n; i += b.lanes) {
    const VU16 fresh = hn::Load(d, b.cost + i);
    const VU16 sum = hn::Sub(hn::Add(hn::Load(d, b.column_sum + i), fresh), hn::Load(d, slot + i));
    hn::Store(sum, d, b.column_sum + i);
    hn::Store(fresh, d, slot + i);
  }
}

// cost[x] = (sum of column_sum[clamp(x - r .. x + r)]) >> sad_shift, by a running sum over x.
void horizontalBox(const SgmParams& p, const StripBuffers& b) {
  const DU16 d;
  const int N = b.lanes, Dp = b.padded, W = p.width, r = p.window / 2;
  auto column = [&](int x) { return b.column_sum + static_cast<std::ptrdiff_t>(std::clamp(x, 0, W - 1)) * Dp; };
  for (int k = 0; k < Dp; k += N) {
    VU16 acc = hn::Zero(d);
    for (int i = -r; i <= r; ++i) acc = hn::Add(acc, hn::Load(d, column(i) + k));
    hn::Store(acc, d, b.running + k);
  }
  for (int x = 0; x < W; ++x) {
    uint16_t* out = b.cost + static_cast<std::ptrdiff_t>(x) * Dp;
    const uint16_t* in = column(x + r);
    const uint16_t* leave = column(x - r - 1);
    for (int k = 0; k < Dp; k += N) {
      VU16 acc = hn::Load(d, b.running + k);
      if (x > 0) {
        acc = hn::Sub(hn::Add(acc, hn::Load(d, in + k)), hn::Load(d, leave + k));
        hn::Store(acc, d, b.running + k);
      }
      hn::Store(hn::ShiftRightSame(acc, p.sad_shift), d, out + k);
    }
  }
}

// Census cost: Hamming distance of the left descriptor to each right descriptor x - k.
void censusCostRow(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y) {
  const hn::Repartition<uint32_t, DU16> d32;
  const hn::Rebind<int32_t, decltype(d32)> di32;
  const hn::Rebind<uint16_t, decltype(d32)> d16h;
  const int N32 = static_cast<int>(hn::Lanes(d32)), Dp = b.padded, W = p.width;
  const int yc = clampRow(y, p.height);
  reverseRow(im.census_right + yc * im.census_stride, W, b.reversed_length, b.census_reversed);
  const uint32_t* left = im.census_left + yc * im.census_stride;
  for (int x = 0; x < W; ++x) {
    const auto l = hn::Set(d32, left[x]);
    const uint32_t* r = b.census_reversed + (W - 1 - x + p.min_disparity);
    uint16_t* o = b.cost + static_cast<std::ptrdiff_t>(x) * Dp;
    for (int k = 0; k < Dp; k += N32) {
      const auto bits = hn::PopulationCount(hn::Xor(l, hn::LoadU(d32, r + k)));
      hn::StoreU(hn::DemoteTo(d16h, hn::BitCast(di32, bits)), d16h, o + k);
    }
  }
}

// Disparities with no right pixel (x - min_disparity - k < 0) get the largest cost.
void maskLeftBorder(const SgmParams& p, const StripBuffers& b) {
  const DU16 d;
  const int N = b.lanes, Dp = b.padded;
  const VU16 worst = hn::Set(d, static_cast<uint16_t>(p.max_cost));
  const int last = std::min(p.width, p.min_disparity + Dp);
  for (int x = 0; x < last; ++x) {
    uint16_t* c = b.cost + static_cast<std::ptrdiff_t>(x) * Dp;
    const VU16 max_k = hn::Set(d, static_cast<uint16_t>(std::max(-1, x - p.min_disparity)));
    for (int k = 0; k < Dp; k += N) {
      // x - min_d - k < 0  <=>  k > x - min_d; all lanes when x < min_d.
      const auto beyond = x < p.min_disparity ? hn::FirstN(d, N) : hn::Gt(hn::Iota(d, k), max_k);
      hn::Store(hn::IfThenElse(beyond, worst, hn::Load(d, c + k)), d, c + k);
    }
  }
}

// Brings the cost row to image row y; `first` starts a pass there, otherwise y = previous y + dy.
void costRow(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y, int dy,
             bool first) {
  if (p.census) {
    censusCostRow(p, im, b, y);
  } else {
    if (first) {
      initColumnSums(p, im, b, y);
    } else {
      slideColumnSums(p, im, b, y, dy);
    }
    horizontalBox(p, b);
  }
  maskLeftBorder(p, b);
}

// ---------------------------------------------------------------------------------------------
// Aggregation along the paths, and the winner.

void resetPaths(const StripBuffers& b, uint16_t sentinel) {
  const std::size_t pixels = static_cast<std::size_t>(b.width) + 2;
  for (int i = 0; i < kPrevRowPaths; ++i) {
    for (uint16_t* row : {b.path_prev[i], b.path_cur[i]}) {
      for (std::size_t px = 0; px < pixels; ++px) {
        uint16_t* pixel = row + px * b.pixel_stride;
        std::fill(pixel, pixel + b.lanes, sentinel);
        std::fill(pixel + b.lanes, pixel + b.lanes + b.padded, 0);
        std::fill(pixel + b.lanes + b.padded, pixel + b.pixel_stride, sentinel);
      }
    }
    std::fill(b.min_prev[i], b.min_prev[i] + pixels, 0);
    std::fill(b.min_cur[i], b.min_cur[i] + pixels, 0);
  }
  for (uint16_t* pixel : {b.along[0], b.along[1]}) {
    std::fill(pixel, pixel + b.pixel_stride, sentinel);
    std::fill(pixel + b.lanes, pixel + b.lanes + b.padded, 0);
  }
}

struct PathStep {
  const uint16_t* prev;  // predecessor's path costs
  uint16_t min_prev;     // their minimum
  uint16_t p2;           // P2 for this step
  uint16_t* out;         // where the new path costs go
};

// Grey level difference -> adapted P2 (Hirschmueller: smaller penalty across intensity edges).
struct PenaltyTable {
  uint16_t p2[256];
};

PenaltyTable makePenaltyTable(const SgmParams& p) {
  PenaltyTable t;
  for (int g = 0; g < 256; ++g) {
    int value = p.p2;
    if (p.adaptive_p2) {
      value = static_cast<int>(std::lround(p.p2 / (1.0 + g / p.p2_gradient_scale)));
      value = std::max(value, p.p1 + 1);
      value = std::min(value, p.p2);
    }
    t.p2[g] = static_cast<uint16_t>(value);
  }
  return t;
}

// Winner, sub-pixel offset and PKRN of one pixel's path sums (b.sums); returns the integer winner
// k (or -1) and writes the outputs.
int selectWinner(const SgmParams& p, const StripBuffers& b, int x, uint16_t* s, float* disparity,
                 float* confidence) {
  const DU16 d;
  const hn::RebindToSigned<DU16> di;
  const int N = b.lanes, D = p.num_disparities, Dp = b.padded;
  // Disparities k with a right pixel: k <= x - min_d.
  const int valid = std::min(D, x - p.min_disparity + 1);
  if (valid <= 0) {
    *disparity = std::numeric_limits<float>::infinity();
    *confidence = 0.0f;
    return -1;
  }
  // Lanes past D hold sentinel sums, larger than any real one; only at the left border do lanes
  // without a right pixel need masking.
  if (valid < D) std::fill(s + valid, s + Dp, kNoCost);
  VU16 best = hn::Load(d, s);
  for (int k = N; k < Dp; k += N) best = hn::Min(best, hn::Load(d, s + k));
  const uint16_t c1 = minLane(d, best);
  int winner = 0;
  for (int k = 0; k < Dp; k += N) {
    const intptr_t lane = hn::FindFirstTrue(d, hn::Eq(hn::Load(d, s + k), hn::Set(d, c1)));
    if (lane >= 0) {
      winner = k + static_cast<int>(lane);
      break;
    }
  }
  // Second minimum: outside winner-1..winner+1 (neighbours of the winner are the same match
  // seen at a sub-pixel offset), or anywhere but the winner.
  const int reach = p.pkrn_exclude_neighbours ? 1 : 0;
  const auto lo = hn::Set(di, static_cast<int16_t>(winner - reach - 1));
  const auto hi = hn::Set(di, static_cast<int16_t>(winner + reach + 1));
  VU16 second = hn::Set(d, kNoCost);
  for (int k = 0; k < Dp; k += N) {
    const auto index = hn::Iota(di, k);
    const auto near = hn::RebindMask(d, hn::And(hn::Gt(index, lo), hn::Lt(index, hi)));
    second = hn::Min(second, hn::IfThenElse(near, hn::Set(d, kNoCost), hn::Load(d, s + k)));
  }
  const uint16_t c2 = minLane(d, second);
  // PKRN = c2 / c1, with one cost unit added to both so that it is defined for c1 = 0. A pixel
  // with no second candidate at all is as ambiguous as it can be: confidence 1.
  const float pkrn = c2 == kNoCost ? 1.0f : (c2 + 1.0f) / (c1 + 1.0f);
  if (pkrn < p.min_confidence) {
    *disparity = std::numeric_limits<float>::infinity();
    *confidence = 0.0f;
    return -1;
  }
  float offset = 0.0f;
  if (p.subpixel && winner > 0 && winner + 1 < valid) {
    const int below = s[winner - 1], above = s[winner + 1];
    const int denominator = below + above - 2 * c1;
    if (denominator > 0) offset = static_cast<float>(below - above) / (2.0f * denominator);
  }
  *disparity = static_cast<float>(p.min_disparity + winner) + offset;
  *confidence = pkrn;
  return winner;
}

// Right image's best sum per pixel (for the LR check): right pixel xr = x - min_d - k, stored
// reversed at W - 1 - xr so that one left pixel's disparities are contiguous.
void updateRightMinimum(const SgmParams& p, const StripBuffers& b, int x, const uint16_t* sums) {
  const DU16 d;
  const int N = b.lanes;
  const std::ptrdiff_t base = p.width - 1 - x + p.min_disparity;
  for (int k = 0; k < b.padded; k += N) {
    const VU16 m = hn::LoadU(d, b.right_min + base + k);
    const VU16 a = hn::LoadU(d, b.right_arg + base + k);
    const VU16 s = hn::Load(d, sums + k);
    const auto better = hn::Lt(s, m);
    hn::StoreU(hn::Min(m, s), d, b.right_min + base + k);
    hn::StoreU(hn::IfThenElse(better, hn::Iota(d, k), a), d, b.right_arg + base + k);
  }
}

// Marks pixels whose right-image winner disagrees by more than lr_max_diff.
void leftRightCheck(const SgmParams& p, const StripBuffers& b, float* disparity, float* confidence) {
  for (int x = 0; x < p.width; ++x) {
    const int k = b.winner[x];
    if (k < 0) continue;
    const int xr = x - p.min_disparity - k;
    const int right_k = b.right_arg[p.width - 1 - xr];
    if (std::abs(right_k - k) > p.lr_max_diff) {
      disparity[x] = std::numeric_limits<float>::infinity();
      confidence[x] = 0.0f;
    }
  }
}

enum class RowOutput { kNone, kStoreSums, kWinner };

// Aggregates the 4 paths of one pass over row y (dx = +1: left to right; -1: right to left; the
// previous row is y - dx, i.e. above for the first pass and below for the second).
// `stored_sums`: first-pass sums to add (8-path second pass) or to write (8-path first pass).
void aggregateRow(const SgmParams& p, const SgmImages& im, StripBuffers& b, const PenaltyTable& pen,
                  int y, int dx, bool first_row, RowOutput output, uint16_t* stored_sums,
                  bool add_stored, float* disparity, float* confidence) {
  const DU16 d;
  const int N = b.lanes, Dp = b.padded, W = p.width, D = p.num_disparities;
  const VU16 p1 = hn::Set(d, static_cast<uint16_t>(p.p1));
  const uint16_t sentinel = static_cast<uint16_t>(p.max_cost + p.p2 + p.p1);
  const VU16 sentinel_v = hn::Set(d, sentinel);
  const auto last_mask = hn::FirstN(d, D - (Dp - N));  // data lanes of the last vector
  const uint8_t* row = im.left + y * im.image_stride;
  const uint8_t* prev_row = im.left + (y - dx) * im.image_stride;  // inside the image border
  if (output == RowOutput::kWinner && p.lr_check) {
    std::fill(b.right_min, b.right_min + b.reversed_length, kNoCost);
    std::fill(b.right_arg, b.right_arg + b.reversed_length, 0);
  }
  uint16_t along_min = 0;
  int along_cur = 0;
  // The along-row path starts fresh at the first pixel of the row.
  std::fill(b.along[1] + N, b.along[1] + N + Dp, 0);
  for (int i = 0; i < W; ++i) {
    const int x = dx > 0 ? i : W - 1 - i;
    const uint16_t* c = b.cost + static_cast<std::ptrdiff_t>(x) * Dp;
    const int g_along = std::abs(row[x] - row[x - dx]);
    const int g_up = std::abs(row[x] - prev_row[x]);
    const int g_up_back = std::abs(row[x] - prev_row[x - dx]);
    const int g_up_fwd = std::abs(row[x] - prev_row[x + dx]);
    const uint16_t* along_prev = b.along[1 - along_cur] + N;
    if (i == 0) along_min = 0;
    PathStep steps[4] = {
        {along_prev, along_min, pen.p2[g_along], b.along[along_cur] + N},
        {b.pathPixel(b.path_prev[0], x), first_row ? uint16_t(0) : b.min_prev[0][x + 1], pen.p2[g_up],
         b.pathPixel(b.path_cur[0], x)},
        {b.pathPixel(b.path_prev[1], x - dx), first_row ? uint16_t(0) : b.min_prev[1][x - dx + 1],
         pen.p2[g_up_back], b.pathPixel(b.path_cur[1], x)},
        {b.pathPixel(b.path_prev[2], x + dx), first_row ? uint16_t(0) : b.min_prev[2][x + dx + 1],
         pen.p2[g_up_fwd], b.pathPixel(b.path_cur[2], x)},
    };
    VU16 mins[4] = {sentinel_v, sentinel_v, sentinel_v, sentinel_v};
    // Along-row predecessor, rolled through registers: vectors k - 1, k and k + 1 (the pads
    // before and after the Dp values hold sentinels).
    VU16 along_before = hn::Load(d, along_prev - N);
    VU16 along_here = hn::Load(d, along_prev);
    uint16_t* stored = stored_sums ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp : nullptr;
    uint16_t* sums = b.sums + static_cast<std::ptrdiff_t>(x) * Dp;
    for (int k = 0; k < Dp; k += N) {
      const VU16 cost = hn::Load(d, c + k);
      VU16 sum = add_stored ? hn::Load(d, stored + k) : hn::Zero(d);
      const VU16 along_after = hn::Load(d, along_prev + k + N);
      for (int r = 0; r < 4; ++r) {
        const PathStep& st = steps[r];
        VU16 same, step1;
        if (r == 0) {
          same = along_here;
          step1 = hn::Add(hn::Min(shiftInPrevious(along_before, along_here), shiftInNext(along_here, along_after)), p1);
        } else {
          same = hn::Load(d, st.prev + k);
          step1 = hn::Add(hn::Min(hn::LoadU(d, st.prev + k - 1), hn::LoadU(d, st.prev + k + 1)), p1);
        }
        const VU16 jump = hn::Set(d, static_cast<uint16_t>(st.min_prev + st.p2));
        VU16 path = hn::Add(cost, hn::Sub(hn::Min(hn::Min(same, step1), jump), hn::Set(d, st.min_prev)));
        if (k + N == Dp) path = hn::IfThenElse(last_mask, path, sentinel_v);
        hn::Store(path, d, st.out + k);
        mins[r] = hn::Min(mins[r], path);
        sum = hn::Add(sum, path);
      }
      hn::Store(sum, d, output == RowOutput::kStoreSums ? stored + k : sums + k);
      along_before = along_here;
      along_here = along_after;
    }
    along_min = minLane(d, mins[0]);
    for (int r = 1; r < 4; ++r) b.min_cur[r - 1][x + 1] = minLane(d, mins[r]);
    along_cur = 1 - along_cur;
  }
  // Winners after the row, not inside the path loop: pixels are independent here, so their
  // horizontal minima overlap in the out-of-order core instead of lengthening the path chain.
  if (output == RowOutput::kWinner) {
    for (int x = 0; x < W; ++x) {
      uint16_t* sums = b.sums + static_cast<std::ptrdiff_t>(x) * Dp;
      // The right image's minimum first: selectWinner() masks lanes of the sums.
      if (p.lr_check) updateRightMinimum(p, b, x, sums);
      b.winner[x] = static_cast<int16_t>(selectWinner(p, b, x, sums, disparity + x, confidence + x));
    }
  }
  for (int r = 0; r < kPrevRowPaths; ++r) {
    std::swap(b.path_prev[r], b.path_cur[r]);
    std::swap(b.min_prev[r], b.min_cur[r]);
  }
  if (output == RowOutput::kWinner && p.lr_check) leftRightCheck(p, b, disparity, confidence);
}

void MatchStripImpl(const SgmParams& p, const SgmImages& im, int row_begin, int row_end,
                    int overlap, SgmWorkspace& ws, const SgmOutput& out) {
  StripBuffers b = carveBuffers(p, ws);
  const PenaltyTable pen = makePenaltyTable(p);
  const uint16_t sentinel = static_cast<uint16_t>(p.max_cost + p.p2 + p.p1);
  uint16_t* volume = nullptr;
  if (p.eight_paths) {
    const std::size_t n = static_cast<std::size_t>(row_end - row_begin) * p.width * b.padded;
    if (ws.volume_elements < n) {
      ws.volume = hwy::AllocateAligned<uint16_t>(n);
      ws.volume_elements = n;
    }
    volume = ws.volume.get();
  }
  auto volumeRow = [&](int y) {
    return volume + static_cast<std::size_t>(y - row_begin) * p.width * b.padded;
  };
  auto outRow = [&](float* base, int y) { return base + y * out.stride; };

  // Pass 1: top-down, left to right.
  resetPaths(b, sentinel);
  const int top = std::max(0, row_begin - overlap);
  for (int y = top; y < row_end; ++y) {
    costRow(p, im, b, y, +1, y == top);
    const bool own = y >= row_begin;
    if (!own) {
      aggregateRow(p, im, b, pen, y, +1, y == top, RowOutput::kNone, nullptr, false, nullptr, nullptr);
    } else if (!p.eight_paths) {
      aggregateRow(p, im, b, pen, y, +1, y == top, RowOutput::kWinner, nullptr, false,
                   outRow(out.disparity, y), outRow(out.confidence, y));
    } else {
      aggregateRow(p, im, b, pen, y, +1, y == top, RowOutput::kStoreSums, volumeRow(y), false,
                   nullptr, nullptr);
    }
  }
  if (!p.eight_paths) return;

  // Pass 2: bottom-up, right to left; adds the first pass's sums and takes the winner.
  resetPaths(b, sentinel);
  const int bottom = std::min(p.height, row_end + overlap) - 1;
  for (int y = bottom; y >= row_begin; --y) {
    costRow(p, im, b, y, -1, y == bottom);
    if (y >= row_end) {
      aggregateRow(p, im, b, pen, y, -1, y == bottom, RowOutput::kNone, nullptr, false, nullptr, nullptr);
    } else {
      aggregateRow(p, im, b, pen, y, -1, y == bottom, RowOutput::kWinner, volumeRow(y), true,
                   outRow(out.disparity, y), outRow(out.confidence, y));
    }
  }
}

void CensusTransformImpl(const uint8_t* image, std::ptrdiff_t stride, int width, int row_begin,
                         int row_end, int window, uint32_t* out, std::ptrdiff_t out_stride) {
  const hn::ScalableTag<uint32_t> d32;
  const hn::Rebind<uint8_t, decltype(d32)> d8;
  const int N = static_cast<int>(hn::Lanes(d32));
  const int r = window / 2;
  for (int y = row_begin; y < row_end; ++y) {
    const uint8_t* centre_row = image + y * stride;
    uint32_t* o = out + y * out_stride;
    int x = 0;
    for (; x + N <= width; x += N) {
      const auto centre = hn::PromoteTo(d32, hn::LoadU(d8, centre_row + x));
      auto bits = hn::Zero(d32);
      for (int dy = -r; dy <= r; ++dy) {
        for (int dxo = -r; dxo <= r; ++dxo) {
          if (dy == 0 && dxo == 0) continue;
          const auto nb = hn::PromoteTo(d32, hn::LoadU(d8, centre_row + dy * stride + x + dxo));
          const auto less = hn::VecFromMask(d32, hn::Lt(nb, centre));
          bits = hn::Or(hn::ShiftLeft<1>(bits), hn::And(less, hn::Set(d32, 1u)));
        }
      }
      hn::StoreU(bits, d32, o + x);
    }
    for (; x < width; ++x) {
      uint32_t bits = 0;
      for (int dy = -r; dy <= r; ++dy) {
        for (int dxo = -r; dxo <= r; ++dxo) {
          if (dy == 0 && dxo == 0) continue;
          bits = (bits << 1) | (centre_row[dy * stride + x + dxo] < centre_row[x] ? 1u : 0u);
        }
      }
      o[x] = bits;
    }
  }
}

int VectorLanesImpl() { return static_cast<int>(hn::Lanes(DU16())); }

}  // namespace HWY_NAMESPACE
}  // namespace cenote::pipeline::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::pipeline::detail {

HWY_EXPORT(MatchStripImpl);
HWY_EXPORT(CensusTransformImpl);
HWY_EXPORT(VectorLanesImpl);

void matchStrip(const SgmParams& params, const SgmImages& images, int row_begin, int row_end,
                int overlap, SgmWorkspace& workspace, const SgmOutput& output) {
  HWY_DYNAMIC_DISPATCH(MatchStripImpl)(params, images, row_begin, row_end, overlap, workspace, output);
}

void censusTransform(const uint8_t* image, std::ptrdiff_t image_stride, int width, int row_begin,
                     int row_end, int window, uint32_t* out, std::ptrdiff_t out_stride) {
  HWY_DYNAMIC_DISPATCH(CensusTransformImpl)(image, image_stride, width, row_begin, row_end, window,
                                            out, out_stride);
}

int sgmVectorLanes() { return HWY_DYNAMIC_DISPATCH(VectorLanesImpl)(); }

}  // namespace cenote::pipeline::detail
#endif
