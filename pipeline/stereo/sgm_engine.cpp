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
// Band (coarse to fine): path rows hold [kBandDisparities values][2 kBandDisparities sentinels]
// per pixel, the values of disparities [band_start, + kBandDisparities) less their minimum; see
// sgm_band-inl.h.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "pipeline/stereo/sgm_engine.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "pipeline/stereo/sgm_engine.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::pipeline::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef CENOTE_SGM_MAX_LANES
#define CENOTE_SGM_MAX_LANES 32
#endif
using DU16 = hn::CappedTag<uint16_t, CENOTE_SGM_MAX_LANES>;
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

// minLane() in every lane. On AVX-512 the minimum stays in vector registers (no round trip
// through a general register): the along-row path waits for it at every pixel.
template <class D>
HWY_INLINE hn::Vec<D> minLaneBroadcast(D d, hn::Vec<D> v) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  if constexpr (hn::MaxLanes(D()) == 32) {
    const __m256i m256 = _mm256_min_epu16(_mm512_castsi512_si256(v.raw), _mm512_extracti64x4_epi64(v.raw, 1));
    const __m128i m128 = _mm_min_epu16(_mm256_castsi256_si128(m256), _mm256_extracti128_si256(m256, 1));
    return hn::Vec<D>{_mm512_broadcastw_epi16(_mm_minpos_epu16(m128))};
  }
#endif
  return hn::Set(d, minLane(d, v));
}

// The lanes of the concatenation [lo, hi] from lane kOffset on (0 <= kOffset <= lanes): one vector
// out of two adjacent ones, in registers.
template <int kOffset, class V>
HWY_INLINE V lanesFrom(V lo, V hi) {
  constexpr int kLanes = sizeof(V) / sizeof(uint16_t);
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  if constexpr (kLanes == 32) {
    alignas(64) static constexpr std::array<uint16_t, 32> kIndex = [] {
      std::array<uint16_t, 32> index{};
      for (int i = 0; i < 32; ++i) index[i] = static_cast<uint16_t>(kOffset + i);  // >= 32: from hi
      return index;
    }();
    return V{_mm512_permutex2var_epi16(lo.raw, _mm512_load_si512(kIndex.data()), hi.raw)};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  if constexpr (kLanes == 16) {
    // alignr shifts within each 128-bit half: pair every half with the one that follows it.
    const __m256i middle = _mm256_permute2x128_si256(lo.raw, hi.raw, 0x21);  // [upper half of lo, lower of hi]
    if constexpr (kOffset < 8) return V{_mm256_alignr_epi8(middle, lo.raw, 2 * kOffset)};
    return V{_mm256_alignr_epi8(hi.raw, middle, 2 * (kOffset - 8))};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_SSSE3
  if constexpr (kLanes == 8) return V{_mm_alignr_epi8(hi.raw, lo.raw, 2 * kOffset)};
#endif
  const DU16 d;
  HWY_ALIGN uint16_t lanes[2 * kLanes];
  hn::Store(lo, d, lanes);
  hn::Store(hi, d, lanes + hn::Lanes(d));
  return hn::LoadU(d, lanes + kOffset);
}

// Lane shifts across a whole vector: [prev[N-1], cur[0..N-2]] (the d-1 neighbours of `cur`) and
// [cur[1..N-1], next[0]] (the d+1 neighbours). The along-row path needs them in registers: the
// previous pixel's path costs were stored just before, and an unaligned reload of them would miss
// store-to-load forwarding on every vector (it dominated the profile).
template <class V>
HWY_INLINE V shiftInPrevious(V prev, V cur) {
  return lanesFrom<sizeof(V) / sizeof(uint16_t) - 1>(prev, cur);
}

template <class V>
HWY_INLINE V shiftInNext(V cur, V next) {
  return lanesFrom<1>(cur, next);
}

// Winners are taken for this many pixels at a time, after their paths: the pixels are
// independent there, so the long chain of horizontal minima of one overlaps the next's.
constexpr int kWinnerBatch = 16;

// Carves the strip's buffers out of the workspace.
//
// Path rows hold the previous row's path costs for the three directions that come from the row
// before (0: same x, 1: x - dx, 2: x + dx), updated in place as the row is swept: direction 0
// reads and writes pixel x; direction 2 reads x + dx, which the sweep has not reached yet.
// Direction 1 reads x - dx, which the sweep has just passed, so its new values go to a second
// row (index 3) that trades places with row 1 after every image row. Four rows keep the strip's
// working set in the L2 cache.
struct StripBuffers {
  int width = 0;
  int lanes = 0;         // N
  int padded = 0;        // Dp: disparities rounded up to N
  int pixel_stride = 0;  // Dp, plus N sentinel lanes when Dp == D; band: 3 kBandDisparities
  int lead = 0;          // sentinel lanes before pixel -1 of a path row: N; band: 2 kBandDisparities
  bool band = false;     // coarse-to-fine band (SgmImages::band_start)
  uint16_t* path[4] = {};
  uint16_t* path_min[4] = {};      // W + 2 each, pixel x at x + 1 (full search; the band stores paths less their minimum)
  uint16_t* along[2] = {};         // [N sentinels][Dp][N sentinels]: previous and current pixel
  uint16_t* column_sum = nullptr;  // SAD: [x][Dp] sums over the window rows
  uint8_t* ring = nullptr;         // SAD: window rows of [x][Dp] absolute differences
  // Band SAD (instead of column_sum and ring): the window's right rows reversed and widened
  // ([window][reversed_length], slot by image row) and its left rows widened ([window][W], the
  // same slots), see sgm_band-inl.h.
  uint16_t* band_rows = nullptr;
  uint16_t* band_left_rows = nullptr;
  uint16_t* running = nullptr;       // SAD: Dp, running horizontal window sum
  uint16_t* sums = nullptr;          // [kWinnerBatch][Dp]: path sums of the pixels awaiting their winner
  uint16_t* batch_best = nullptr;    // [kWinnerBatch][N]: lane-wise minimum of each pixel's sums
  uint16_t* batch_index = nullptr;   // [kWinnerBatch][N]: and the first disparity that has it
  uint16_t* batch_second = nullptr;  // [kWinnerBatch][N]: lane-wise second smallest sum
  uint16_t* iota = nullptr;          // Dp: 0, 1, 2, ...
  uint16_t* right_min = nullptr;     // LR check: best sum per right pixel, stored reversed
  uint16_t* right_arg = nullptr;
  int16_t* winner = nullptr;          // W: integer winner per pixel of the row (-1 = invalid)
  uint8_t* right_reversed = nullptr;  // SAD: entering right row, reversed and padded
  uint16_t* census_reversed[2] = {};  // census: right row's low and high 16 bits, reversed
  int16_t* band_shift[4] = {};        // band: W each, the predecessors' shifts of a row (bandShifts())
  int reversed_length = 0;

  uint16_t* pathPixel(uint16_t* row, int x) const { return row + lead + static_cast<std::ptrdiff_t>(x + 1) * pixel_stride; }
};

std::size_t alignUp(std::size_t n, std::size_t a) { return (n + a - 1) / a * a; }

StripBuffers carveBuffers(const SgmParams& p, SgmWorkspace& ws, bool band) {
  const DU16 d;
  StripBuffers b;
  b.width = p.width;
  b.lanes = static_cast<int>(hn::Lanes(d));
  b.band = band;
  b.padded = static_cast<int>(alignUp(p.num_disparities, b.lanes));
  b.pixel_stride = band ? 3 * kBandDisparities : b.padded + (b.padded > p.num_disparities ? 0 : b.lanes);
  b.lead = band ? 2 * kBandDisparities : b.lanes;
  const std::size_t W = p.width, Dp = b.padded, N = b.lanes;
  b.reversed_length = static_cast<int>(alignUp(W + p.min_disparity + Dp + 2 * N, 64));
  const std::size_t rev = b.reversed_length;
  const std::size_t path_row = (W + 2) * b.pixel_stride + 2 * b.lead;
  const std::size_t along = std::max<std::size_t>(Dp + 2 * N, 5 * kBandDisparities);
  const bool band_sad = band && !p.census;
  const std::size_t sad = p.census ? 0 : band_sad ? p.window * (rev + W) : W * Dp + (W * Dp * p.window + 1) / 2;
  // Every piece is rounded up to 64 elements by take(); 32 pieces at most.
  const std::size_t total = 4 * (path_row + W + 2) + 2 * along + sad + 2 * Dp + kWinnerBatch * (Dp + 3 * N) + 2 * rev + W +
                            (rev / 2 + 32) + 2 * rev + 4 * W + 32 * 64;
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
  for (int i = 0; i < 4; ++i) {
    b.path[i] = take(path_row);
    b.path_min[i] = take(W + 2);
  }
  b.along[0] = take(along);
  b.along[1] = take(along);
  if (band_sad) {
    b.band_rows = take(p.window * rev);
    b.band_left_rows = take(p.window * W);
  } else if (!p.census) {
    b.column_sum = take(W * Dp);
    b.ring = reinterpret_cast<uint8_t*>(take((W * Dp * p.window + 1) / 2));  // window rows of bytes
  }
  b.running = take(Dp);
  b.sums = take(kWinnerBatch * Dp);
  b.batch_best = take(kWinnerBatch * N);
  b.batch_index = take(kWinnerBatch * N);
  b.batch_second = take(kWinnerBatch * N);
  b.iota = take(Dp);
  for (std::size_t k = 0; k < Dp; ++k) b.iota[k] = static_cast<uint16_t>(k);
  b.right_min = take(rev);
  b.right_arg = take(rev);
  b.winner = reinterpret_cast<int16_t*>(take(W));
  b.right_reversed = reinterpret_cast<uint8_t*>(take(rev / 2 + 32));
  b.census_reversed[0] = take(rev);
  b.census_reversed[1] = take(rev);
  for (int16_t*& shift : b.band_shift) shift = reinterpret_cast<int16_t*>(take(W));
  return b;
}

// ---------------------------------------------------------------------------------------------
// Matching cost, built on the fly for each pixel as the row is swept.

int clampRow(int y, int height) { return std::clamp(y, 0, height - 1); }
int clampColumn(int x, int width) { return std::clamp(x, 0, width - 1); }
int ringSlot(int y, int window) { return ((y % window) + window) % window; }

// Right image row reversed: reversed[j] = row[W - 1 - j], so that the right pixels x - k of one
// left pixel x are contiguous in k. Left of the image the row repeats its first pixel (those
// disparities are masked out of the cost). `Out` may be wider than `In`.
template <typename In, typename Out>
void reverseRow(const In* row, int width, int length, Out* reversed) {
  for (int j = 0; j < width; ++j) reversed[j] = row[width - 1 - j];
  for (int j = width; j < length; ++j) reversed[j] = row[0];
}

using D8 = hn::Rebind<uint8_t, DU16>;

// |left - right| for the disparities of vector k, as bytes.
HWY_INLINE hn::Vec<D8> absDiffBytes(uint8_t left, const uint8_t* right_reversed_at_x, int k) {
  const D8 d8;
  const auto l = hn::Set(d8, left);
  const auto r = hn::LoadU(d8, right_reversed_at_x + k);
  return hn::Or(hn::SaturatedSub(l, r), hn::SaturatedSub(r, l));
}

const uint8_t* reversedAt(const SgmParams& p, const uint8_t* reversed, int x) {
  return reversed + (p.width - 1 - x + p.min_disparity);
}

// Column sums over rows [y - r, y + r] for the first row of a pass: every ring slot filled.
void initColumnSums(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y) {
  const DU16 d;
  const D8 d8;
  const int r = p.window / 2, N = b.lanes, Dp = b.padded, W = p.width;
  const std::size_t n = static_cast<std::size_t>(W) * Dp;
  std::fill(b.column_sum, b.column_sum + n, 0);
  for (int yy = y - r; yy <= y + r; ++yy) {
    const int yc = clampRow(yy, p.height);
    uint8_t* slot = b.ring + static_cast<std::size_t>(ringSlot(yy, p.window)) * n;
    reverseRow(im.right + yc * im.image_stride, W, b.reversed_length, b.right_reversed);
    const uint8_t* left = im.left + yc * im.image_stride;
    for (int x = 0; x < W; ++x) {
      const uint8_t* rev = reversedAt(p, b.right_reversed, x);
      for (int k = 0; k < Dp; k += N) {
        const auto ad = absDiffBytes(left[x], rev, k);
        const std::size_t at = static_cast<std::size_t>(x) * Dp + k;
        hn::Store(ad, d8, slot + at);
        hn::Store(hn::Add(hn::Load(d, b.column_sum + at), hn::PromoteTo(d, ad)), d, b.column_sum + at);
      }
    }
  }
}

// Where the matching cost of the current row comes from, set up once per row.
struct CostSource {
  // SAD: the entering image row of the vertical window (its differences replace those of the
  // row leaving the window, in the same ring slot) and whether columns must be updated at all.
  bool update_columns = false;
  const uint8_t* entering_left = nullptr;
  uint8_t* entering_slot = nullptr;
  // Census: the left descriptors of the row.
  const uint32_t* census_left = nullptr;
};

// Column c of the entering row: where its differences come from and go to (resolved once per
// column, outside the loop over disparity vectors).
struct EnteringColumn {
  uint8_t left = 0;                // left image value at c
  const uint8_t* right = nullptr;  // reversed right row at c
  uint8_t* slot = nullptr;         // ring slot of the entering row, at c
  uint16_t* sum = nullptr;         // column sums, at c
};

EnteringColumn enteringColumn(const SgmParams& p, const StripBuffers& b, const CostSource& src, int c) {
  const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(c) * b.padded;
  return {src.entering_left[c], reversedAt(p, b.right_reversed, c), src.entering_slot + at, b.column_sum + at};
}

// The entering row's differences for vector k of a column: swapped into the ring slot in place of
// the leaving row's; returns the updated column sum.
HWY_INLINE VU16 updateColumn(const EnteringColumn& col, int k) {
  const DU16 d;
  const D8 d8;
  const auto ad = absDiffBytes(col.left, col.right, k);
  const VU16 old = hn::PromoteTo(d, hn::Load(d8, col.slot + k));
  hn::Store(ad, d8, col.slot + k);
  const VU16 sum = hn::Sub(hn::Add(hn::Load(d, col.sum + k), hn::PromoteTo(d, ad)), old);
  hn::Store(sum, d, col.sum + k);
  return sum;
}

// Prepares row y (dy: direction of the sweep over rows, dx: over columns) and the window sum of
// the sweep's first pixel.
CostSource beginCostRow(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y, int dy, int dx,
                        bool first_row) {
  const DU16 d;
  CostSource src;
  const int W = p.width, Dp = b.padded, N = b.lanes;
  if (p.census) {
    const int yc = clampRow(y, p.height);
    const uint32_t* right = im.census_right + yc * im.census_stride;
    for (int j = 0; j < b.reversed_length; ++j) {
      const uint32_t c = right[j < W ? W - 1 - j : 0];
      b.census_reversed[0][j] = static_cast<uint16_t>(c & 0xFFFF);
      b.census_reversed[1][j] = static_cast<uint16_t>(c >> 16);
    }
    src.census_left = im.census_left + yc * im.census_stride;
    return src;
  }
  const int r = p.window / 2;
  if (first_row) {
    initColumnSums(p, im, b, y);
  } else {
    const int entering = y + dy * r;
    const int yc = clampRow(entering, p.height);
    src.update_columns = true;
    src.entering_left = im.left + yc * im.image_stride;
    src.entering_slot = b.ring + static_cast<std::size_t>(ringSlot(entering, p.window)) * W * Dp;
    reverseRow(im.right + yc * im.image_stride, W, b.reversed_length, b.right_reversed);
  }
  // Window sum of the first pixel x0: columns x0 - r .. x0 + r (clamped); the columns ahead of
  // x0 in the sweep direction are brought to the new row first.
  const int x0 = dx > 0 ? 0 : W - 1;
  for (int k = 0; k < Dp; k += N) {
    if (src.update_columns) {
      for (int i = 0; i <= r; ++i) {
        const int c = x0 + dx * i;
        if (c >= 0 && c < W) updateColumn(enteringColumn(p, b, src, c), k);
      }
    }
    VU16 acc = hn::Zero(d);
    for (int i = -r; i <= r; ++i) {
      acc = hn::Add(acc, hn::Load(d, b.column_sum + static_cast<std::size_t>(clampColumn(x0 + i, W)) * Dp + k));
    }
    hn::Store(acc, d, b.running + k);
  }
  return src;
}

// ---------------------------------------------------------------------------------------------
// Aggregation along the paths, and the winner.

// The path cost of a disparity a path pixel does not hold (lanes past D; in the band, outside the
// pixel's band): it loses against every real predecessor even after + P1. Path costs are at most
// max_cost + P2; in the band the minimum of a predecessor may be up to max_cost + P2 as well (a
// pixel's band may miss its predecessor's entirely), so the sentinel must also lose against
// min + P2 there.
uint16_t pathSentinel(const SgmParams& p, bool band) {
  return static_cast<uint16_t>(p.max_cost + (band ? 2 : 1) * p.p2 + p.p1);
}

// Every path row to "no predecessor": zero costs (so that a path starts with L = C), sentinels in
// the lanes past D.
// Band: each pixel's kBandDisparities values, the rest of its stride sentinels.
void resetPaths(const SgmParams& p, const StripBuffers& b, uint16_t sentinel) {
  const int D = b.band ? kBandDisparities : p.num_disparities;
  const std::size_t pixels = static_cast<std::size_t>(b.width) + 2;
  for (int i = 0; i < 4; ++i) {
    uint16_t* row = b.path[i];
    std::fill(row, row + b.lead, sentinel);
    for (std::size_t px = 0; px < pixels; ++px) {
      uint16_t* pixel = row + b.lead + px * b.pixel_stride;
      std::fill(pixel, pixel + D, 0);
      std::fill(pixel + D, pixel + b.pixel_stride, sentinel);
    }
    uint16_t* end = row + b.lead + pixels * b.pixel_stride;
    std::fill(end, end + b.lead, sentinel);
    std::fill(b.path_min[i], b.path_min[i] + pixels, 0);
  }
}

// The along-row path starts fresh at the first pixel of every row.
void resetAlong(const SgmParams& p, const StripBuffers& b, uint16_t sentinel) {
  const int N = b.lanes, Dp = b.padded;
  for (uint16_t* pixel : {b.along[0], b.along[1]}) {
    std::fill(pixel, pixel + Dp + 2 * N, sentinel);
    std::fill(pixel + N, pixel + N + p.num_disparities, 0);
  }
}

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

// Integer results of the winner search for a batch of pixels; finishWinners() turns them into
// disparities and confidences (float arithmetic, for all pixels of the batch at once).
struct WinnerBatch {
  HWY_ALIGN int32_t winner[kWinnerBatch];  // -1: no disparity
  HWY_ALIGN int32_t c1[kWinnerBatch];      // smallest sum
  HWY_ALIGN int32_t c2[kWinnerBatch];      // second smallest outside the winner's span (kNoCost: none)
  HWY_ALIGN int32_t below[kWinnerBatch];   // sums at winner - 1 and + 1; both c1 without sub-pixel
  HWY_ALIGN int32_t above[kWinnerBatch];
};

// The winner search of one pixel, lane by lane, as its vectors of path sums come: each lane's
// smallest sum, the first disparity that has it and its second smallest sum. pickWinner() takes
// the winner from them; the kernels keep them in batch slots until then.
struct LaneWinners {
  VU16 best, best_index, second_best;

  // The sums of one vector of disparities (`disparities`: the index of each lane's).
  HWY_INLINE void add(VU16 sum, VU16 disparities) {
    second_best = hn::Min(second_best, hn::Max(best, sum));
    best_index = hn::IfThenElse(hn::Lt(sum, best), disparities, best_index);
    best = hn::Min(best, sum);
  }
  // Into batch slot `slot`, where flushWinnerBatch() reads them.
  HWY_INLINE void store(const StripBuffers& b, int slot) const {
    const DU16 d;
    const std::ptrdiff_t at = slot * static_cast<std::ptrdiff_t>(hn::Lanes(d));  // b.lanes
    hn::Store(best, d, b.batch_best + at);
    hn::Store(best_index, d, b.batch_index + at);
    hn::Store(second_best, d, b.batch_second + at);
  }
};

// Before the first vector of sums.
HWY_INLINE LaneWinners noWinners() {
  const DU16 d;
  return {hn::Set(d, kNoCost), hn::Zero(d), hn::Set(d, kNoCost)};
}

// Winner and second minimum of one pixel's path sums `s` (searched lane by lane in `lanes`), into
// slot j of the batch. The sums are those of disparities [first, first + D) (the band, or the
// whole range with first = 0), padded to Dp; indices and `lanes.best_index` count from `first`.
HWY_INLINE void pickWinner(const SgmParams& p, const StripBuffers& b, int x, uint16_t* s, LaneWinners lanes,
                           WinnerBatch& out, int j, int first, int D, int Dp) {
  const DU16 d;
  const int N = b.lanes;
  // Disparities k with a right pixel: k <= x - min_d.
  const int valid_in_range = std::min(p.num_disparities, x - p.min_disparity + 1);
  const int valid = std::min(D, valid_in_range - first);
  if (valid <= 0 || (p.invalidate_truncated && valid_in_range < p.num_disparities)) {
    out.winner[j] = -1;
    return;
  }
  // Lanes past D hold sentinel sums, larger than any real one; only at the left border do lanes
  // without a right pixel need masking.
  if (valid < D) {
    std::fill(s + valid, s + Dp, kNoCost);
    lanes.best = hn::Set(d, kNoCost);
    lanes.second_best = lanes.best;
    for (int k = 0; k < Dp; k += N) lanes.add(hn::Load(d, s + k), hn::Load(d, b.iota + k));
  }
  const VU16 best = lanes.best, best_index = lanes.best_index;
  // Smallest sum, and the smallest disparity that has it: each lane already holds its own
  // minimum and first index (branch-free; searching the vectors for the winner mispredicts).
  const uint16_t c1 = minLane(d, best);
  // With one vector (a band, or a short range) lane i holds disparity i: the first lane with c1.
  const int winner = Dp <= N ? static_cast<int>(hn::FindKnownFirstTrue(d, hn::Eq(best, hn::Set(d, c1))))
                             : minLane(d, hn::IfThenElse(hn::Eq(best, hn::Set(d, c1)), best_index, hn::Set(d, kNoCost)));
  // Second minimum: outside winner-1..winner+1 (neighbours of the winner are the same match
  // seen at a sub-pixel offset), or anywhere but the winner. A lane holds disparities N apart,
  // so the excluded span takes at most one disparity from it: if that is the lane's first
  // minimum, the lane's smallest outside the span is its second smallest, otherwise its minimum.
  // In unsigned arithmetic, indices below winner - reach wrap around to large values, so one
  // comparison finds the span.
  const int reach = p.pkrn_exclude_neighbours ? 1 : 0;
  const VU16 first_near = hn::Set(d, static_cast<uint16_t>(winner - reach));
  const VU16 span = hn::Set(d, static_cast<uint16_t>(2 * reach + 1));
  const auto best_is_near = hn::Lt(hn::Sub(best_index, first_near), span);
  out.winner[j] = first + winner;
  out.c1[j] = c1;
  out.c2[j] = minLane(d, hn::IfThenElse(best_is_near, lanes.second_best, best));
  const bool subpixel = p.subpixel && winner > 0 && winner + 1 < valid;
  out.below[j] = subpixel ? s[winner - 1] : c1;
  out.above[j] = subpixel ? s[winner + 1] : c1;
}

// Disparity, sub-pixel offset and PKRN of batch slots [0, count): pixel j of the batch is image
// column x0 + dx j. Writes the outputs and the integer winner per column (-1 where invalid).
void finishWinners(const SgmParams& p, const WinnerBatch& in, int count, int x0, int dx, float* disparity,
                   float* confidence, int16_t* winners) {
  const hn::ScalableTag<float> df;
  const hn::RebindToSigned<decltype(df)> di;
  const hn::Rebind<int16_t, decltype(di)> d16;
  const int L = static_cast<int>(hn::Lanes(df));
  const auto one = hn::Set(df, 1.0f), zero = hn::Zero(df), two = hn::Set(df, 2.0f);
  const auto min_confidence = hn::Set(df, p.min_confidence);
  const auto no_cost = hn::Set(di, kNoCost);
  for (int j0 = 0; j0 < count; j0 += L) {
    const auto winner = hn::Load(di, in.winner + j0);
    const auto c1 = hn::Load(di, in.c1 + j0), c2 = hn::Load(di, in.c2 + j0);
    const auto below = hn::Load(di, in.below + j0), above = hn::Load(di, in.above + j0);
    const auto c1_plus = hn::Add(hn::ConvertTo(df, c1), one), c2_plus = hn::Add(hn::ConvertTo(df, c2), one);
    // PKRN = c2 / c1, with one cost unit added to both so that it is defined for c1 = 0. A pixel
    // with no second candidate at all is as ambiguous as it can be: confidence 1.
    const auto no_second = hn::RebindMask(df, hn::Eq(c2, no_cost));
    const auto pkrn = hn::IfThenElse(no_second, one, hn::Div(c2_plus, c1_plus));
    const auto rejected = hn::IfThenElse(no_second, hn::VecFromMask(df, hn::Lt(one, min_confidence)),
                                         hn::VecFromMask(df, hn::Lt(c2_plus, hn::Mul(min_confidence, c1_plus))));
    const auto kept = hn::And(hn::RebindMask(df, hn::Gt(winner, hn::Set(di, -1))), hn::Not(hn::MaskFromVec(rejected)));
    // Parabola through (winner - 1, below), (winner, c1), (winner + 1, above).
    const auto denominator = hn::Sub(hn::Add(below, above), hn::Add(c1, c1));
    const auto offset = hn::IfThenElse(
        hn::RebindMask(df, hn::Gt(denominator, hn::Zero(di))),
        hn::Div(hn::ConvertTo(df, hn::Sub(below, above)), hn::Mul(two, hn::ConvertTo(df, denominator))), zero);
    const auto value = hn::Add(hn::ConvertTo(df, hn::Add(winner, hn::Set(di, p.min_disparity))), offset);
    auto out_disparity = hn::IfThenElse(kept, value, hn::Set(df, std::numeric_limits<float>::infinity()));
    auto out_confidence = hn::IfThenElse(kept, pkrn, zero);
    auto out_winner = hn::IfThenElse(hn::RebindMask(di, kept), winner, hn::Set(di, -1));
    // Columns x0 + dx j0 .. x0 + dx (j0 + n - 1): stored from the leftmost, reversed right to left.
    const int n = std::min(L, count - j0);
    const int left = dx > 0 ? x0 + j0 : x0 - j0 - (n - 1);
    if (n == L) {
      if (dx < 0) {
        out_disparity = hn::Reverse(df, out_disparity);
        out_confidence = hn::Reverse(df, out_confidence);
        out_winner = hn::Reverse(di, out_winner);
      }
      hn::StoreU(out_disparity, df, disparity + left);
      hn::StoreU(out_confidence, df, confidence + left);
      hn::StoreU(hn::DemoteTo(d16, out_winner), d16, winners + left);
      continue;
    }
    HWY_ALIGN float lanes_disparity[hn::MaxLanes(df)], lanes_confidence[hn::MaxLanes(df)];
    HWY_ALIGN int32_t lanes_winner[hn::MaxLanes(df)];
    hn::Store(out_disparity, df, lanes_disparity);
    hn::Store(out_confidence, df, lanes_confidence);
    hn::Store(out_winner, di, lanes_winner);
    for (int j = 0; j < n; ++j) {
      const int x = x0 + dx * (j0 + j);
      disparity[x] = lanes_disparity[j];
      confidence[x] = lanes_confidence[j];
      winners[x] = static_cast<int16_t>(lanes_winner[j]);
    }
  }
}

// Right image's best sum per pixel (for the LR check): right pixel xr = x - min_d - k, stored
// reversed at W - 1 - xr so that one left pixel's disparities are contiguous. Ties keep the
// smaller k, whichever way the row is swept.
// `sums` hold disparities [first, first + count).
HWY_INLINE void updateRightMinimum(const SgmParams& p, const StripBuffers& b, int x, const uint16_t* sums, int dx,
                                   int first, int count) {
  const DU16 d;
  const int N = static_cast<int>(hn::Lanes(d));  // b.lanes, known to the compiler: one vector unrolls
  const std::ptrdiff_t base = p.width - 1 - x + p.min_disparity + first;
  // In locals: the stores may alias the struct's fields.
  uint16_t* const right_min = b.right_min + base;
  uint16_t* const right_arg = b.right_arg + base;
  const uint16_t* const iota = b.iota;
  const VU16 offset = hn::Set(d, static_cast<uint16_t>(first));
  for (int k = 0; k < count; k += N) {
    const VU16 m = hn::LoadU(d, right_min + k);
    const VU16 a = hn::LoadU(d, right_arg + k);
    const VU16 s = hn::Load(d, sums + k);
    // Left to right, k grows for a fixed right pixel: keep the first. Right to left, k shrinks:
    // an equal sum replaces.
    const auto better = dx > 0 ? hn::Lt(s, m) : hn::Not(hn::Lt(m, s));
    hn::StoreU(hn::Min(m, s), d, right_min + k);
    hn::StoreU(hn::IfThenElse(better, hn::Add(hn::Load(d, iota + k), offset), a), d, right_arg + k);
  }
}

// Winners of the pixels whose best / index / second-best vectors are stored in batch slots
// 0..slot (slot being row position i of the row swept along dx; N lanes per stored vector). Pixel
// j's sums are at b.sums + j * b.padded and hold disparities [first[j], first[j] + D) with stride
// Dp (first null: every pixel from 0). With one vector of sums (Dp == N) the stored vectors are
// not read (the kernels may skip them): the sums are their own lane-wise minimum, lane k holds
// disparity k, and no lane has a second value. `update_right`: each pixel's sums go into the LR
// check's right-image minimum first (the band kernel does that in its pixel loop instead).
HWY_INLINE void flushWinnerBatch(const SgmParams& p, const StripBuffers& b, int i, int slot, int dx, int N,
                                 const int32_t* first, int D, int Dp, bool update_right, float* disparity,
                                 float* confidence) {
  const DU16 d;
  WinnerBatch batch;
  const int x0 = dx > 0 ? i - slot : p.width - 1 - (i - slot);  // the batch's first pixel
  for (int j = 0; j <= slot; ++j) {
    const int xj = x0 + dx * j;
    uint16_t* sums = b.sums + j * b.padded;
    const int first_j = first != nullptr ? first[j] : 0;
    // The right image's minimum first: pickWinner() masks lanes of the sums.
    if (update_right) updateRightMinimum(p, b, xj, sums, dx, first_j, Dp);
    const bool one_vector = Dp == N;
    const LaneWinners lanes{hn::Load(d, one_vector ? sums : b.batch_best + j * N),
                            hn::Load(d, one_vector ? b.iota : b.batch_index + j * N),
                            one_vector ? hn::Set(d, kNoCost) : hn::Load(d, b.batch_second + j * N)};
    pickWinner(p, b, xj, sums, lanes, batch, j, first_j, D, Dp);
  }
  finishWinners(p, batch, slot + 1, x0, dx, disparity, confidence, b.winner);
}

// Marks pixels whose right-image winner disagrees by more than lr_max_diff. A vector of pixels at a
// time, their right winners gathered, without branches (one per pixel mispredicted: 3 % of the band
// search's CPU time on AVX-512).
void leftRightCheck(const SgmParams& p, const StripBuffers& b, float* disparity, float* confidence) {
  const hn::ScalableTag<int32_t> di;
  const hn::RebindToFloat<decltype(di)> df;
  const hn::Rebind<int16_t, decltype(di)> d16;
  const int L = static_cast<int>(hn::Lanes(di)), W = p.width;
  // Pixel x's right winner is right_arg[W - 1 - xr], xr = x - min_d - k: the low half of the 32
  // bits there (the buffer is longer than any index read).
  const int32_t* const right = reinterpret_cast<const int32_t*>(b.right_arg);
  const auto lanes = hn::Iota(di, 0), none = hn::Set(di, -1), low = hn::Set(di, 0xFFFF);
  const auto max_diff = hn::Set(di, p.lr_max_diff);
  const auto infinity = hn::Set(df, std::numeric_limits<float>::infinity());
  int x = 0;
  for (; x + L <= W; x += L) {
    const auto k = hn::PromoteTo(di, hn::LoadU(d16, b.winner + x));
    const auto valid = hn::Gt(k, none);
    const auto at = hn::Add(hn::Sub(hn::Set(di, W - 1 + p.min_disparity - x), lanes), k);
    const auto right_k = hn::And(hn::GatherOffset(di, right, hn::ShiftLeft<1>(hn::IfThenElseZero(valid, at))), low);
    const auto rejected = hn::RebindMask(df, hn::And(valid, hn::Gt(hn::Abs(hn::Sub(right_k, k)), max_diff)));
    hn::StoreU(hn::IfThenElse(rejected, infinity, hn::LoadU(df, disparity + x)), df, disparity + x);
    hn::StoreU(hn::IfThenZeroElse(rejected, hn::LoadU(df, confidence + x)), df, confidence + x);
  }
  for (; x < W; ++x) {
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

// The smaller of a path pixel's costs at disparities d - 1 and d + 1, for the d of each lane at
// `at` (sentinel lanes pad both ends of the pixel).
HWY_INLINE VU16 neighbourMin(const uint16_t* at) {
  const DU16 d;
  return hn::Min(hn::LoadU(d, at - 1), hn::LoadU(d, at + 1));
}

// The sum over the four paths of the pixel's vector k of disparities, plus the first pass's sums
// (`sums_in`: 8 paths, second pass; null otherwise); stored in `sums_out`.
HWY_INLINE VU16 storePathSum(VU16 l0, VU16 l1, VU16 l2, VU16 l3, const uint16_t* sums_in, uint16_t* sums_out, int k) {
  const DU16 d;
  VU16 sum = hn::Add(hn::Add(l0, l1), hn::Add(l2, l3));
  if (sums_in) sum = hn::Add(sum, hn::Load(d, sums_in + k));
  hn::Store(sum, d, sums_out + k);
  return sum;
}

// After pixel x: the minima of its three stored paths (vertical, forward and backward diagonal),
// which the next row's pixels read for their P2 term, into rows b.path_min[0], [2] and [3].
HWY_INLINE void storePathMinima(uint16_t* min_vertical, uint16_t* min_fwd, uint16_t* min_back, int x, VU16 mins_vertical,
                                VU16 mins_fwd, VU16 mins_back) {
  const DU16 d;
  min_vertical[x + 1] = minLane(d, mins_vertical);
  min_fwd[x + 1] = minLane(d, mins_fwd);
  min_back[x + 1] = minLane(d, mins_back);
}

// After a row (both search modes): direction 1's new row becomes the one the next image row
// reads (pixels -1 and W of both rows are never written: they stay "no predecessor"); then the
// left-right check of the row's winners.
void finishRow(const SgmParams& p, StripBuffers& b, RowOutput output, float* disparity, float* confidence) {
  std::swap(b.path[1], b.path[3]);
  std::swap(b.path_min[1], b.path_min[3]);
  if (output == RowOutput::kWinner && p.lr_check) leftRightCheck(p, b, disparity, confidence);
}

// What the cost of a pixel needs, known at compile time for the common cases. kGeneral decides
// at run time (first pixel of a row, left border, SAD window columns outside the image).
enum class PixelKind { kGeneral, kSadInterior, kCensusInterior };

// One row of one pass: builds the matching cost on the fly, advances the four paths and sums
// them (dx = +1: left to right, previous row above; -1: right to left, previous row below).
// Path directions: 0 along the row (from x - dx, kept in `along`), 1 from (x, y - dx),
// 2 from (x - dx, y - dx), 3 from (x + dx, y - dx); rows 0..2 of b.path hold directions 1..3
// (row 3: direction 2's new costs).
// `stored_sums`: first-pass sums to add (8-path second pass) or to write (8-path first pass).
void aggregateRowFull(const SgmParams& p, const SgmImages& im, StripBuffers& b, const PenaltyTable& pen, int y, int dx,
                      bool first_row, RowOutput output, uint16_t* stored_sums, bool add_stored, float* disparity,
                      float* confidence) {
  const DU16 d;
  const int N = b.lanes, Dp = b.padded, W = p.width, D = p.num_disparities, r = p.window / 2;
  const VU16 p1 = hn::Set(d, static_cast<uint16_t>(p.p1));
  const uint16_t sentinel = pathSentinel(p, false);
  const VU16 sentinel_v = hn::Set(d, sentinel);
  const VU16 worst_cost = hn::Set(d, static_cast<uint16_t>(p.max_cost));
  const auto last_mask = hn::FirstN(d, D - (Dp - N));  // data lanes of the last vector
  const uint8_t* row = im.guide + y * im.image_stride;
  const uint8_t* prev_row = im.guide + (y - dx) * im.image_stride;  // inside the image border
  const CostSource src = beginCostRow(p, im, b, y, dx, dx, first_row);
  if (output == RowOutput::kWinner && p.lr_check) {
    std::fill(b.right_min, b.right_min + b.reversed_length, kNoCost);
    std::fill(b.right_arg, b.right_arg + b.reversed_length, 0);
  }
  resetAlong(p, b, sentinel);
  VU16 along_min = hn::Zero(d);
  int along_cur = 0;
  for (int i = 0; i < W; ++i) {
    const int x = dx > 0 ? i : W - 1 - i;
    // SAD window columns: the one entering ahead of x and the one leaving behind it.
    const int ahead = x + dx * r;
    const bool update_ahead = src.update_columns && i > 0 && ahead >= 0 && ahead < W;
    const uint16_t* add_column = p.census ? nullptr
                                          : b.column_sum + static_cast<std::ptrdiff_t>(clampColumn(ahead, W)) * Dp;
    const uint16_t* leave_column = p.census
                                       ? nullptr
                                       : b.column_sum + static_cast<std::ptrdiff_t>(clampColumn(x - dx * (r + 1), W)) * Dp;
    const bool left_border = x - p.min_disparity < D;
    const bool no_match = x < p.min_disparity;
    const VU16 max_valid_k = hn::Set(d, static_cast<uint16_t>(no_match ? 0 : x - p.min_disparity));
    const uint16_t census_lo = p.census ? static_cast<uint16_t>(src.census_left[x] & 0xFFFF) : 0;
    const uint16_t census_hi = p.census ? static_cast<uint16_t>(src.census_left[x] >> 16) : 0;
    const std::ptrdiff_t census_base = W - 1 - x + p.min_disparity;

    // Predecessors of the four directions (see above) and their penalties. Everything the
    // vector loop reads is copied into locals: Highway's stores may alias anything, and the
    // compiler would otherwise reload struct fields after every store.
    const uint16_t* const along_prev = b.along[1 - along_cur] + N;
    uint16_t* const along_out = b.along[along_cur] + N;
    uint16_t* const vertical = b.pathPixel(b.path[0], x);
    const uint16_t* const back = b.pathPixel(b.path[1], x - dx);
    uint16_t* const back_out = b.pathPixel(b.path[3], x);
    const uint16_t* const fwd = b.pathPixel(b.path[2], x + dx);
    uint16_t* const fwd_out = b.pathPixel(b.path[2], x);
    const uint16_t min_vertical = b.path_min[0][x + 1];
    const uint16_t min_back = b.path_min[1][x - dx + 1], min_fwd = b.path_min[2][x + dx + 1];
    const VU16 min_along_v = along_min, min_vertical_v = hn::Set(d, min_vertical);
    const VU16 min_back_v = hn::Set(d, min_back), min_fwd_v = hn::Set(d, min_fwd);
    const VU16 jump_along = hn::Add(along_min, hn::Set(d, pen.p2[std::abs(row[x] - row[x - dx])]));
    const VU16 jump_vertical = hn::Set(d, static_cast<uint16_t>(min_vertical + pen.p2[std::abs(row[x] - prev_row[x])]));
    const VU16 jump_back = hn::Set(d, static_cast<uint16_t>(min_back + pen.p2[std::abs(row[x] - prev_row[x - dx])]));
    const VU16 jump_fwd = hn::Set(d, static_cast<uint16_t>(min_fwd + pen.p2[std::abs(row[x] - prev_row[x + dx])]));
    const int slot = i % kWinnerBatch;
    uint16_t* const sums_out = output == RowOutput::kStoreSums ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp
                                                               : b.sums + slot * Dp;
    const uint16_t* const sums_in = add_stored ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp : nullptr;
    const uint16_t* const iota = b.iota;
    uint16_t* const running_sum = b.running;
    const uint16_t* const census_right_lo = b.census_reversed[0] + census_base;
    const uint16_t* const census_right_hi = b.census_reversed[1] + census_base;
    const bool census = p.census, has_running = !census && i > 0;
    const int sad_shift = p.sad_shift;

    VU16 mins_along = sentinel_v, mins_vertical = sentinel_v, mins_back = sentinel_v, mins_fwd = sentinel_v;
    LaneWinners winners = noWinners();
    // Along-row predecessor, rolled through registers: vectors k - 1, k and k + 1 (the pads
    // before and after the Dp values hold sentinels).
    VU16 along_before = hn::Load(d, along_prev - N);
    VU16 along_here = hn::Load(d, along_prev);
    VU16 vertical_pending = sentinel_v;
    // SAD column entering the window ahead of x.
    const EnteringColumn ahead_column = update_ahead ? enteringColumn(p, b, src, ahead) : EnteringColumn{};

    // One vector of disparities; `is_last` (a compile-time constant) keeps the lanes past D at
    // the sentinel. Forced inline: GCC otherwise calls it, reloading every capture from memory
    // on each vector (about a fifth of the matching time).
    // `kind` (a compile-time constant, see PixelKind) removes the per-vector branches of the
    // pixels that are neither first in the row nor at the left border: nearly all of them.
    auto vector_step = [&](int k, auto is_last, auto kind) HWY_ATTR __attribute__((always_inline)) {
      constexpr PixelKind kKind = decltype(kind)::value;
      const bool is_census = kKind == PixelKind::kGeneral ? census : kKind == PixelKind::kCensusInterior;
      const bool running = kKind == PixelKind::kGeneral ? has_running : kKind == PixelKind::kSadInterior;
      const bool update = kKind == PixelKind::kGeneral ? update_ahead : kKind == PixelKind::kSadInterior;
      const bool border = kKind == PixelKind::kGeneral && left_border;
      VU16 cost;
      if (is_census) {
        const VU16 lo = hn::Xor(hn::Set(d, census_lo), hn::LoadU(d, census_right_lo + k));
        const VU16 hi = hn::Xor(hn::Set(d, census_hi), hn::LoadU(d, census_right_hi + k));
        cost = hn::Add(hn::PopulationCount(lo), hn::PopulationCount(hi));
      } else {
        VU16 acc = hn::Load(d, running_sum + k);
        if (running) {
          const VU16 add = update ? updateColumn(ahead_column, k) : hn::Load(d, add_column + k);
          acc = hn::Sub(hn::Add(acc, add), hn::Load(d, leave_column + k));
          hn::Store(acc, d, running_sum + k);
        }
        cost = hn::ShiftRightSame(acc, sad_shift);
      }
      if (border) {
        // x - min_d - k < 0: no right pixel, largest cost.
        const auto beyond = no_match ? hn::FirstN(d, N) : hn::Gt(hn::Load(d, iota + k), max_valid_k);
        cost = hn::IfThenElse(beyond, worst_cost, cost);
      }
      // L = C + min(L(d), min(L(d-1), L(d+1)) + P1, min_k L + P2) - min_k L.
      auto step = [&](VU16 same, VU16 neighbours, VU16 jump, VU16 min_prev) HWY_ATTR __attribute__((always_inline)) {
        const VU16 path = hn::Add(cost, hn::Sub(hn::Min(hn::Min(same, hn::Add(neighbours, p1)), jump), min_prev));
        if constexpr (decltype(is_last)::value) return hn::IfThenElse(last_mask, path, sentinel_v);
        return path;
      };
      const VU16 along_after = hn::Load(d, along_prev + k + N);
      const VU16 l0 = step(along_here,
                           hn::Min(shiftInPrevious(along_before, along_here), shiftInNext(along_here, along_after)),
                           jump_along, min_along_v);
      const VU16 l1 = step(hn::Load(d, vertical + k), neighbourMin(vertical + k), jump_vertical, min_vertical_v);
      const VU16 l2 = step(hn::Load(d, back + k), neighbourMin(back + k), jump_back, min_back_v);
      const VU16 l3 = step(hn::Load(d, fwd + k), neighbourMin(fwd + k), jump_fwd, min_fwd_v);
      hn::Store(l0, d, along_out + k);
      // Direction 1 overwrites the pixel it reads: vector k's neighbour loads still need vector
      // k - 1's old last lane, so each vector is stored one step late.
      if (k > 0) hn::Store(vertical_pending, d, vertical + k - N);
      vertical_pending = l1;
      hn::Store(l2, d, back_out + k);
      hn::Store(l3, d, fwd_out + k);
      mins_along = hn::Min(mins_along, l0);
      mins_vertical = hn::Min(mins_vertical, l1);
      mins_back = hn::Min(mins_back, l2);
      mins_fwd = hn::Min(mins_fwd, l3);
      winners.add(storePathSum(l0, l1, l2, l3, sums_in, sums_out, k), hn::Load(d, iota + k));
      along_before = along_here;
      along_here = along_after;
    };
    auto vector_loop = [&](auto kind) HWY_ATTR __attribute__((always_inline)) {
      for (int k = 0; k + N < Dp; k += N) vector_step(k, std::false_type(), kind);
      vector_step(Dp - N, std::true_type(), kind);
    };
    if (!left_border && !census && has_running && update_ahead) {
      vector_loop(std::integral_constant<PixelKind, PixelKind::kSadInterior>());
    } else if (!left_border && census) {
      vector_loop(std::integral_constant<PixelKind, PixelKind::kCensusInterior>());
    } else {
      vector_loop(std::integral_constant<PixelKind, PixelKind::kGeneral>());
    }
    hn::Store(vertical_pending, d, vertical + Dp - N);
    along_min = minLaneBroadcast(d, mins_along);
    storePathMinima(b.path_min[0], b.path_min[2], b.path_min[3], x, mins_vertical, mins_fwd, mins_back);
    along_cur = 1 - along_cur;
    if (output == RowOutput::kWinner) {
      winners.store(b, slot);
      if (slot == kWinnerBatch - 1 || i == W - 1) {
        flushWinnerBatch(p, b, i, slot, dx, N, nullptr, D, Dp, p.lr_check, disparity, confidence);
      }
    }
  }
  finishRow(p, b, output, disparity, confidence);
}

// Coarse-to-fine band search: aggregateRowBand().
#include "pipeline/stereo/sgm_band-inl.h"

void MatchStripImpl(const SgmParams& p, const SgmImages& im, int row_begin, int row_end, int overlap, SgmWorkspace& ws,
                    const SgmOutput& out) {
  const bool band = im.band_start != nullptr;
  StripBuffers b = carveBuffers(p, ws, band);
  const PenaltyTable pen = makePenaltyTable(p);
  const uint16_t sentinel = pathSentinel(p, band);
  auto aggregateRow = &aggregateRowFull;
  if (band) {
    switch (p.census ? 0 : p.window) {
      case 0: aggregateRow = &aggregateRowBand<0>; break;
      case 1: aggregateRow = &aggregateRowBand<1>; break;
      case 3: aggregateRow = &aggregateRowBand<3>; break;
      case 5: aggregateRow = &aggregateRowBand<5>; break;
      case 7: aggregateRow = &aggregateRowBand<7>; break;
      default: aggregateRow = &aggregateRowBand<9>; break;
    }
  }
  uint16_t* volume = nullptr;
  if (p.eight_paths) {
    const std::size_t n = static_cast<std::size_t>(row_end - row_begin) * p.width * b.padded;
    if (ws.volume_elements < n) {
      ws.volume = hwy::AllocateAligned<uint16_t>(n);
      ws.volume_elements = n;
    }
    volume = ws.volume.get();
  }
  auto volumeRow = [&](int y) { return volume + static_cast<std::size_t>(y - row_begin) * p.width * b.padded; };
  auto outRow = [&](float* base, int y) { return base + y * out.stride; };

  // Pass 1: top-down, left to right.
  resetPaths(p, b, sentinel);
  const int top = std::max(0, row_begin - overlap);
  for (int y = top; y < row_end; ++y) {
    const bool first = y == top;
    if (y < row_begin) {
      aggregateRow(p, im, b, pen, y, +1, first, RowOutput::kNone, nullptr, false, nullptr, nullptr);
    } else if (!p.eight_paths) {
      aggregateRow(p, im, b, pen, y, +1, first, RowOutput::kWinner, nullptr, false, outRow(out.disparity, y),
                   outRow(out.confidence, y));
    } else {
      aggregateRow(p, im, b, pen, y, +1, first, RowOutput::kStoreSums, volumeRow(y), false, nullptr, nullptr);
    }
  }
  if (!p.eight_paths) return;

  // Pass 2: bottom-up, right to left; adds the first pass's sums and takes the winner.
  resetPaths(p, b, sentinel);
  const int bottom = std::min(p.height, row_end + overlap) - 1;
  for (int y = bottom; y >= row_begin; --y) {
    const bool first = y == bottom;
    if (y >= row_end) {
      aggregateRow(p, im, b, pen, y, -1, first, RowOutput::kNone, nullptr, false, nullptr, nullptr);
    } else {
      aggregateRow(p, im, b, pen, y, -1, first, RowOutput::kWinner, volumeRow(y), true, outRow(out.disparity, y),
                   outRow(out.confidence, y));
    }
  }
}

void CensusTransformImpl(const uint8_t* image, std::ptrdiff_t stride, int width, int row_begin, int row_end, int window,
                         uint32_t* out, std::ptrdiff_t out_stride) {
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

void matchStrip(const SgmParams& params, const SgmImages& images, int row_begin, int row_end, int overlap,
                SgmWorkspace& workspace, const SgmOutput& output) {
  HWY_DYNAMIC_DISPATCH(MatchStripImpl)(params, images, row_begin, row_end, overlap, workspace, output);
}

void censusTransform(const uint8_t* image, std::ptrdiff_t image_stride, int width, int row_begin, int row_end, int window,
                     uint32_t* out, std::ptrdiff_t out_stride) {
  HWY_DYNAMIC_DISPATCH(CensusTransformImpl)(image, image_stride, width, row_begin, row_end, window, out, out_stride);
}

int sgmVectorLanes() { return HWY_DYNAMIC_DISPATCH(VectorLanesImpl)(); }

}  // namespace cenote::pipeline::detail
#endif
