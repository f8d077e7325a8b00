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
//
// Parts, each included once below inside the Highway namespace (not standalone headers):
//   sgm_cost-inl.h         matching cost built on the fly (cost rows, column sums, beginCostRow)
//   sgm_winner-inl.h       winner search and LR check (LaneWinners, flushWinnerBatch, leftRightCheck)
//   sgm_full_search-inl.h  full-search row kernel (aggregateRowFull)
//   sgm_band_bytes-inl.h   what the band kernel needs in byte lanes (census costs that fit a byte)
//   sgm_band-inl.h         coarse-to-fine band row kernel (aggregateRowBand), 16-bit or byte lanes
// This file: the buffers, the helpers the parts share, the strip driver (MatchStripImpl), the
// census transform and the dispatch.

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
// The band's path costs in byte lanes (census costs that fit a byte, sgm_band_bytes-inl.h): one
// band per 256-bit vector (AVX2, AVX-512), two of 128 bits on SSE and NEON.
using DU8 = hn::CappedTag<uint8_t, kBandDisparities>;
// The vectors of path costs of lane type T.
template <class T>
using PathTag = std::conditional_t<sizeof(T) == 1, DU8, DU16>;

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

// The smallest byte lane in every lane. x86: the bytes of each word to their minimum, then one
// PHMINPOSUW.
template <class V>
HWY_INLINE V minByteBroadcast(V v) {
  static_assert(sizeof(hn::TFromV<V>) == 1, "byte lanes");
  const hn::DFromV<V> d;
  constexpr int kLanes = static_cast<int>(hn::MaxLanes(hn::DFromV<V>()));
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  if constexpr (kLanes == 32) {
    __m128i m = _mm_min_epu8(_mm256_castsi256_si128(v.raw), _mm256_extracti128_si256(v.raw, 1));
    m = _mm_min_epu8(m, _mm_srli_epi16(m, 8));  // each word: the smaller of its two bytes
    return V{_mm256_broadcastb_epi8(_mm_minpos_epu16(m))};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_SSE4
  if constexpr (kLanes == 16) {
    const __m128i m = _mm_min_epu8(v.raw, _mm_srli_epi16(v.raw, 8));
    return V{_mm_shuffle_epi8(_mm_minpos_epu16(m), _mm_setzero_si128())};
  }
#endif
  HWY_ALIGN uint8_t lanes[kLanes];
  hn::Store(v, d, lanes);
  return hn::Set(d, *std::min_element(lanes, lanes + kLanes));
}

// minLane() in every lane. On AVX-512 the minimum stays in vector registers (no round trip
// through a general register): the along-row path waits for it at every pixel.
template <class D>
HWY_INLINE hn::Vec<D> minWordBroadcast(D d, hn::Vec<D> v) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  if constexpr (hn::MaxLanes(D()) == 32) {
    const __m256i m256 = _mm256_min_epu16(_mm512_castsi512_si256(v.raw), _mm512_extracti64x4_epi64(v.raw, 1));
    const __m128i m128 = _mm_min_epu16(_mm256_castsi256_si128(m256), _mm256_extracti128_si256(m256, 1));
    return hn::Vec<D>{_mm512_broadcastw_epi16(_mm_minpos_epu16(m128))};
  }
#endif
  return hn::Set(d, minLane(d, v));
}

// The smallest lane of a vector of path costs (bytes or words) in every lane.
template <class D>
HWY_INLINE hn::Vec<D> minLaneBroadcast(D d, hn::Vec<D> v) {
  if constexpr (sizeof(hn::TFromD<D>) == 1) {
    return minByteBroadcast(v);
  } else {
    return minWordBroadcast(d, v);
  }
}

// The lanes of the concatenation [lo, hi] from lane kOffset on (0 <= kOffset <= lanes): one vector
// out of two adjacent ones, in registers. Lanes of 16 bits, or of 8 (the band in bytes).
template <int kOffset, class V>
HWY_INLINE V lanesFrom(V lo, V hi) {
  using T = hn::TFromV<V>;
  constexpr int kLanes = static_cast<int>(hn::MaxLanes(hn::DFromV<V>()));
  [[maybe_unused]] constexpr int kBytes = kLanes * static_cast<int>(sizeof(T));   // unused on the scalar target
  [[maybe_unused]] constexpr int kShift = kOffset * static_cast<int>(sizeof(T));  // in bytes
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  if constexpr (kBytes == 64 && sizeof(T) == 2) {
    alignas(64) static constexpr std::array<uint16_t, 32> kIndex = [] {
      std::array<uint16_t, 32> index{};
      for (int i = 0; i < 32; ++i) index[i] = static_cast<uint16_t>(kOffset + i);  // >= 32: from hi
      return index;
    }();
    return V{_mm512_permutex2var_epi16(lo.raw, _mm512_load_si512(kIndex.data()), hi.raw)};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  if constexpr (kBytes == 32) {
    // alignr shifts within each 128-bit half: pair every half with the one that follows it.
    const __m256i middle = _mm256_permute2x128_si256(lo.raw, hi.raw, 0x21);  // [upper half of lo, lower of hi]
    if constexpr (kShift < 16) return V{_mm256_alignr_epi8(middle, lo.raw, kShift)};
    return V{_mm256_alignr_epi8(hi.raw, middle, kShift - 16)};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_SSSE3
  if constexpr (kBytes == 16) return V{_mm_alignr_epi8(hi.raw, lo.raw, kShift)};
#endif
  const hn::DFromV<V> d;
  HWY_ALIGN T lanes[2 * kLanes];
  hn::Store(lo, d, lanes);
  hn::Store(hi, d, lanes + kLanes);
  return hn::LoadU(d, lanes + kOffset);
}

// Lane shifts across a whole vector: [prev[N-1], cur[0..N-2]] (the d-1 neighbours of `cur`) and
// [cur[1..N-1], next[0]] (the d+1 neighbours). The along-row path needs them in registers: the
// previous pixel's path costs were stored just before, and an unaligned reload of them would miss
// store-to-load forwarding on every vector (it dominated the profile).
template <class V>
HWY_INLINE V shiftInPrevious(V prev, V cur) {
  return lanesFrom<static_cast<int>(hn::MaxLanes(hn::DFromV<V>())) - 1>(prev, cur);
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
  uint8_t* census_bytes[3] = {};      // census, band in bytes: right row's bytes 0, 1, 2, reversed
  int16_t* band_shift[4] = {};        // band: W each, the predecessors' shifts of a row (bandShifts())
  int16_t* zero_starts = nullptr;     // W zeros: the band starts of a full search in one band (MatchStripImpl)
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
  // The band kernel's sums and path pixels hold kBandDisparities values, even for a shorter range.
  b.padded = static_cast<int>(alignUp(std::max(p.num_disparities, band ? kBandDisparities : 0), b.lanes));
  b.pixel_stride = band ? 3 * kBandDisparities : b.padded + (b.padded > p.num_disparities ? 0 : b.lanes);
  b.lead = band ? 2 * kBandDisparities : b.lanes;
  const std::size_t W = p.width, Dp = b.padded, N = b.lanes;
  b.reversed_length = static_cast<int>(alignUp(W + p.min_disparity + Dp + 2 * N, 64));
  const std::size_t rev = b.reversed_length;
  const std::size_t path_row = (W + 2) * b.pixel_stride + 2 * b.lead;
  const std::size_t along = std::max<std::size_t>(Dp + 2 * N, 5 * kBandDisparities);
  const bool band_sad = band && !p.census;
  const std::size_t sad = p.census ? 0 : band_sad ? p.window * (rev + W) : W * Dp + (W * Dp * p.window + 1) / 2;
  // Every piece is rounded up to 64 elements by take(); 32 pieces at most (32 * 64 to spare).
  const std::size_t total = 4 * (path_row + W + 2) + 2 * along + sad + 2 * Dp + kWinnerBatch * (Dp + 3 * N) + 2 * rev + W +
                            (rev / 2 + 32) + 2 * rev + 5 * W + 3 * (rev / 2 + 32) + 32 * 64;
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
  b.zero_starts = reinterpret_cast<int16_t*>(take(W));  // filled by MatchStripImpl where it is used
  if (band && p.census) {
    for (uint8_t*& plane : b.census_bytes) plane = reinterpret_cast<uint8_t*>(take(rev / 2 + 32));
  }
  HWY_DASSERT(next <= ws.buffer.get() + total);
  return b;
}

// Matching cost, built on the fly for each pixel as the row is swept: beginCostRow().
#include "pipeline/stereo/sgm_cost-inl.h"

// ---------------------------------------------------------------------------------------------
// Aggregation along the paths, and the winner.

// Every path row to "no predecessor": zero costs (so that a path starts with L = C), sentinels in
// the lanes past D.
// Band: each pixel's kBandDisparities values, the rest of its stride sentinels; in bytes (T =
// uint8_t, the band only) the rows' memory holds the same layout counted in bytes.
template <class T>
void resetPaths(const SgmParams& p, const StripBuffers& b, T sentinel) {
  const int D = b.band ? kBandDisparities : p.num_disparities;
  const std::size_t pixels = static_cast<std::size_t>(b.width) + 2;
  for (int i = 0; i < 4; ++i) {
    T* row = reinterpret_cast<T*>(b.path[i]);
    std::fill(row, row + b.lead, sentinel);
    for (std::size_t px = 0; px < pixels; ++px) {
      T* pixel = row + b.lead + px * b.pixel_stride;
      std::fill(pixel, pixel + D, T{0});
      std::fill(pixel + D, pixel + b.pixel_stride, sentinel);
    }
    T* end = row + b.lead + pixels * b.pixel_stride;
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

// Winner search and LR check: LaneWinners, flushWinnerBatch(), leftRightCheck().
#include "pipeline/stereo/sgm_winner-inl.h"

enum class RowOutput { kNone, kStoreSums, kWinner };

// The smaller of a path pixel's costs at disparities d - 1 and d + 1, for the d of each lane at
// `at` (sentinel lanes pad both ends of the pixel).
template <class T>
HWY_INLINE hn::Vec<PathTag<T>> neighbourMin(const T* at) {
  const PathTag<T> d;
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

// After a row (both search modes): direction 1's new row becomes the one the next image row
// reads (pixels -1 and W of both rows are never written: they stay "no predecessor"); then the
// left-right check of the row's winners.
void finishRow(const SgmParams& p, StripBuffers& b, RowOutput output, float* disparity, float* confidence) {
  std::swap(b.path[1], b.path[3]);
  std::swap(b.path_min[1], b.path_min[3]);
  if (output == RowOutput::kWinner && p.lr_check) leftRightCheck(p, b, disparity, confidence);
}

// Full search: aggregateRowFull().
#include "pipeline/stereo/sgm_full_search-inl.h"

// Coarse-to-fine band search: aggregateRowBand().
// What the band kernel needs to run in byte lanes: bandFitsBytes(), the census in bytes.
#include "pipeline/stereo/sgm_band_bytes-inl.h"
#include "pipeline/stereo/sgm_band-inl.h"

void MatchStripImpl(const SgmParams& p, const SgmImages& images, int row_begin, int row_end, int overlap, SgmWorkspace& ws,
                    const SgmOutput& out) {
  // A full search of at most kBandDisparities disparities (the coarse level) is one band that
  // starts at 0 everywhere: the band kernel, with the lanes past D held at the full search's
  // sentinel (aggregateRowBand), gives the same path costs and winners, with its paths in
  // registers and stored less their minimum (no rows of minima).
  const bool one_band = images.band_start == nullptr && p.num_disparities <= kBandDisparities;
  const bool band = images.band_start != nullptr || one_band;
  StripBuffers b = carveBuffers(p, ws, band);
  SgmImages im = images;
  if (one_band) {
    std::fill(b.zero_starts, b.zero_starts + p.width, int16_t{0});
    im.band_start = b.zero_starts;
    im.band_stride = 0;  // every row the same
  }
  const PenaltyTable pen = makePenaltyTable(p);
  const uint16_t sentinel = pathSentinel(p, band);
  auto aggregateRow = &aggregateRowFull;
  // Not in one band: the four paths' sum of the lanes past D (the sentinel) would wrap in a byte.
  const bool bytes = band && !one_band && bandFitsBytes(p);
  if (bytes) {
    aggregateRow = censusBytePlanes(p) == 1 ? &aggregateRowBand<0, DU8, 1> : &aggregateRowBand<0, DU8, 3>;
  } else if (band) {
    switch (p.census ? 0 : p.window) {
      case 0: aggregateRow = &aggregateRowBand<0, DU16>; break;
      case 1: aggregateRow = &aggregateRowBand<1, DU16>; break;
      case 3: aggregateRow = &aggregateRowBand<3, DU16>; break;
      case 5: aggregateRow = &aggregateRowBand<5, DU16>; break;
      case 7: aggregateRow = &aggregateRowBand<7, DU16>; break;
      default: aggregateRow = &aggregateRowBand<9, DU16>; break;
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
  auto reset = [&] {
    if (bytes) {
      resetPaths(p, b, static_cast<uint8_t>(sentinel));
    } else {
      resetPaths(p, b, sentinel);
    }
  };

  // Pass 1: top-down, left to right.
  reset();
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
  reset();
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
