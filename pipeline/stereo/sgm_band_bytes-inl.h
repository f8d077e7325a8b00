// sgm_band_bytes-inl.h: the coarse-to-fine band kernel in byte lanes (aggregateRowBandBytes), for
// census costs whose path costs fit in a byte. Compiled once per instruction set as part of
// sgm_engine.cpp, which includes it inside its Highway namespace after sgm_band-inl.h (whose
// predecessor shifts and winner handling it shares): not a standalone header.
// No include guard: sgm_engine.cpp is compiled once per target (hwy/foreach_target.h) and includes
// this file each time.
//
// The recurrence, the sentinels and the layout are those of aggregateRowBand() (sgm_band-inl.h),
// one byte per disparity instead of two: a band of 32 is one 256-bit vector where the 16-bit
// kernel needs two (AVX2) or one of 512 bits (AVX-512), so every path step costs half the vector
// work. It is exact, not an approximation: bandFitsBytes() admits only parameters for which no
// value the recurrence forms exceeds 255 (census 5x5 at the default penalties: path costs at most
// 24 + 30, sentinels 94, sums of four paths at most 216), so every byte holds the same number the
// 16-bit kernel holds, and the four paths' sums, widened to 16 bits, go through the same winner
// search and LR check.

// Whether the band kernel may run in bytes: the largest value it forms (a sentinel plus P1) and
// the sum of four path costs (each at most max_cost + P2) fit in a byte.
bool bandFitsBytes(const SgmParams& p) {
  return p.census && pathSentinel(p, true) + p.p1 <= 255 && 4 * (p.max_cost + p.p2) <= 255;
}

using DU8 = hn::CappedTag<uint8_t, kBandDisparities>;
using VU8 = hn::Vec<DU8>;

// A path row's pixel x in bytes: the 16-bit rows' memory holds the byte layout with the same
// geometry in bytes (lead 2 kBandDisparities, stride 3 kBandDisparities).
HWY_INLINE uint8_t* bytePathPixel(uint16_t* row, int x) {
  constexpr int kStride = 3 * kBandDisparities, kLead = 2 * kBandDisparities;
  return reinterpret_cast<uint8_t*>(row) + kLead + static_cast<std::ptrdiff_t>(x + 1) * kStride;
}

// resetPaths() in bytes: every pixel's band zero ("no predecessor"), the rest sentinels.
void resetBytePaths(const StripBuffers& b, uint8_t sentinel) {
  constexpr int kB = kBandDisparities;
  const int pixels = b.width + 2;
  for (uint16_t* row : b.path) {
    uint8_t* const first = bytePathPixel(row, -1);
    std::fill(first - 2 * kB, first, sentinel);
    for (int px = 0; px < pixels; ++px) {
      uint8_t* pixel = first + static_cast<std::ptrdiff_t>(px) * 3 * kB;
      std::fill(pixel, pixel + kB, 0);
      std::fill(pixel + kB, pixel + 3 * kB, sentinel);
    }
    uint8_t* const end = first + static_cast<std::ptrdiff_t>(pixels) * 3 * kB;
    std::fill(end, end + 2 * kB, sentinel);
  }
}

// The census descriptors of the right row, reversed, one byte plane per 8 bits (plane k holds
// bits 8k..8k+7): a disparity's cost is the sum of the planes' popcounts.
int censusBytePlanes(const SgmParams& p) { return (p.window * p.window - 1 + 7) / 8; }

void beginCensusByteRow(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y) {
  const int W = p.width;
  const uint32_t* right = im.census_right + clampRow(y, p.height) * im.census_stride;
  const int planes = censusBytePlanes(p);
  for (int j = 0; j < b.reversed_length; ++j) {
    const uint32_t c = right[j < W ? W - 1 - j : 0];
    for (int k = 0; k < planes; ++k) b.census_bytes[k][j] = static_cast<uint8_t>(c >> (8 * k));
  }
}

// The lanes of [lo, hi] from lane kOffset on (0 < kOffset < lanes), as lanesFrom() in bytes.
template <int kOffset, class V>
HWY_INLINE V byteLanesFrom(V lo, V hi) {
  constexpr int kLanes = static_cast<int>(hn::MaxLanes(hn::DFromV<V>()));
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  if constexpr (kLanes == 32) {
    const __m256i middle = _mm256_permute2x128_si256(lo.raw, hi.raw, 0x21);  // [upper half of lo, lower of hi]
    if constexpr (kOffset < 16) return V{_mm256_alignr_epi8(middle, lo.raw, kOffset)};
    return V{_mm256_alignr_epi8(hi.raw, middle, kOffset - 16)};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_SSSE3
  if constexpr (kLanes == 16) return V{_mm_alignr_epi8(hi.raw, lo.raw, kOffset)};
#endif
  const hn::DFromV<V> d;
  HWY_ALIGN uint8_t lanes[2 * kLanes];
  hn::Store(lo, d, lanes);
  hn::Store(hi, d, lanes + kLanes);
  return hn::LoadU(d, lanes + kOffset);
}

// The band of the previous pixel on the row (`prev`, lanes past it sentinels) as seen from a band
// starting `shift` disparities later (shiftedBand() in bytes; one vector holds the band).
template <int kOffset, class V>
HWY_INLINE V shiftedByteBand(V prev, V sentinel, int shift) {
  constexpr int kLanes = static_cast<int>(hn::MaxLanes(hn::DFromV<V>()));
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3_DL
  if constexpr (kLanes == 32) {  // VBMI: a byte permutation across the whole vector
    const __m256i index = _mm256_add_epi8(hn::Iota(hn::DFromV<V>(), 0).raw,
                                          _mm256_set1_epi8(static_cast<char>(shift + kOffset)));
    const __mmask32 inside = _mm256_cmplt_epu8_mask(index, _mm256_set1_epi8(32));
    return V{_mm256_mask_permutexvar_epi8(sentinel.raw, inside, index, prev.raw)};
  }
#endif
  const hn::DFromV<V> d;
  HWY_ALIGN uint8_t lanes[3 * kLanes];
  hn::Store(sentinel, d, lanes);
  hn::Store(prev, d, lanes + kLanes);
  hn::Store(sentinel, d, lanes + 2 * kLanes);
  return hn::LoadU(d, lanes + kLanes + std::clamp(shift + kOffset, -kLanes, kLanes));
}

// The smallest lane in every lane. x86: pairs of bytes to words, then one PHMINPOSUW.
template <class V>
HWY_INLINE V byteMinBroadcast(V v) {
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

// A byte vector's lanes, widened to 16 bits: one 16-bit vector of as many lanes, or two of half as many.
template <class D16, class V8>
HWY_INLINE void widenBytes(D16 d16, V8 v, hn::Vec<D16>* out) {
  using D8 = hn::DFromV<V8>;
  if constexpr (hn::MaxLanes(D16()) == hn::MaxLanes(D8())) {
    out[0] = hn::PromoteTo(d16, v);
  } else {
#if HWY_TARGET != HWY_SCALAR  // one lane each there
    const hn::Half<D8> dh;
    out[0] = hn::PromoteTo(d16, hn::LowerHalf(dh, v));
    out[1] = hn::PromoteTo(d16, hn::UpperHalf(dh, v));
#endif
  }
}

HWY_INLINE VU8 byteNeighbourMin(const uint8_t* at) {
  const DU8 d;
  return hn::Min(hn::LoadU(d, at - 1), hn::LoadU(d, at + 1));
}

// One row of one pass, as aggregateRowBand<0>() (census) in bytes: the same path costs, sums,
// winners and LR check, bit for bit. kPlanes: censusBytePlanes().
template <int kPlanes>
void aggregateRowBandBytes(const SgmParams& p, const SgmImages& im, StripBuffers& b, const PenaltyTable& pen, int y, int dx,
                           bool first_row, RowOutput output, uint16_t* stored_sums, bool add_stored, float* disparity,
                           float* confidence) {
  const DU8 d8;
  const DU16 d16;
  constexpr int kB = kBandDisparities;
  constexpr int kN8 = static_cast<int>(hn::MaxLanes(DU8()));
  constexpr int kN16 = static_cast<int>(hn::MaxLanes(DU16()));
  constexpr int kVectors8 = kB / kN8;
  constexpr int kVectors16 = kB / kN16;
  static_assert(kB % kN8 == 0 && kB % kN16 == 0, "the band must be a whole number of vectors");
  static_assert(kN16 == kN8 || 2 * kN16 == kN8, "a byte vector widens to one or two 16-bit vectors");
  constexpr int kStride = 3 * kB;
  const int Dp = b.padded, W = p.width;
  const VU8 p1 = hn::Set(d8, static_cast<uint8_t>(p.p1));
  const VU8 sentinel_v = hn::Set(d8, static_cast<uint8_t>(pathSentinel(p, true)));
  const VU8 worst_cost = hn::Set(d8, static_cast<uint8_t>(p.max_cost));
  const uint8_t* row = im.guide + y * im.image_stride;
  const uint8_t* prev_row = im.guide + (y - dx) * im.image_stride;  // inside the image border
  const int16_t* starts = im.band_start + y * im.band_stride;
  bandShifts(p, im, b, y, dx, first_row);
  const int16_t* const shifts_along = b.band_shift[0];
  const int16_t* const shifts_vertical = b.band_shift[1];
  const int16_t* const shifts_back = b.band_shift[2];
  const int16_t* const shifts_fwd = b.band_shift[3];
  beginCensusByteRow(p, im, b, y);
  const uint32_t* const census_left = im.census_left + clampRow(y, p.height) * im.census_stride;
  if (output == RowOutput::kWinner && p.lr_check) {
    std::fill(b.right_min, b.right_min + b.reversed_length, kNoCost);
    std::fill(b.right_arg, b.right_arg + b.reversed_length, 0);
  }
  // The along path's buffer for shifted reads: [2 kB sentinels][kB: the previous pixel][2 kB sentinels].
  uint8_t* const along_bytes = reinterpret_cast<uint8_t*>(b.along[0]);
  std::fill(along_bytes, along_bytes + 5 * kB, static_cast<uint8_t>(pathSentinel(p, true)));
  uint8_t* const along_buffer = along_bytes + 2 * kB;
  VU8 along[kVectors8];
  for (int j = 0; j < kVectors8; ++j) along[j] = hn::Zero(d8);
  HWY_ALIGN int32_t band_first[kWinnerBatch];
  uint8_t* const path_vertical = bytePathPixel(b.path[0], 0);
  const uint8_t* const path_back = bytePathPixel(b.path[1], 0);
  uint8_t* const path_back_out = bytePathPixel(b.path[3], 0);
  uint8_t* const path_fwd = bytePathPixel(b.path[2], 0);
  const uint16_t* const iota = b.iota;
  uint16_t* const batch_sums = b.sums;
  const uint8_t* const census_right[3] = {b.census_bytes[0], b.census_bytes[1], b.census_bytes[2]};
  const bool adaptive = p.adaptive_p2;
  const VU8 p2_constant = hn::Set(d8, static_cast<uint8_t>(p.p2));
  for (int i = 0; i < W; ++i) {
    const int x = dx > 0 ? i : W - 1 - i;
    const int start = starts[x];
    const int shift_along = shifts_along[x], shift_vertical = shifts_vertical[x];
    const int shift_back = shifts_back[x], shift_fwd = shifts_fwd[x];
    // Lanes from `limit` + 1 on have no right pixel (start + lane > x - min_d): largest cost.
    const int limit = x - p.min_disparity - start;
    const bool border = limit < kB - 1;
    const uint32_t census = census_left[x];
    const std::ptrdiff_t census_base = W - 1 - x + p.min_disparity + start;

    uint8_t* const vertical = path_vertical + static_cast<std::ptrdiff_t>(x) * kStride;
    const uint8_t* const vertical_in = vertical + shift_vertical;
    const uint8_t* const back = path_back + static_cast<std::ptrdiff_t>(x - dx) * kStride + shift_back;
    uint8_t* const back_out = path_back_out + static_cast<std::ptrdiff_t>(x) * kStride;
    const uint8_t* const fwd = path_fwd + static_cast<std::ptrdiff_t>(x + dx) * kStride + shift_fwd;
    uint8_t* const fwd_out = path_fwd + static_cast<std::ptrdiff_t>(x) * kStride;
    auto penalty = [&](uint8_t a, uint8_t b2) HWY_ATTR {
      return adaptive ? hn::Set(d8, static_cast<uint8_t>(pen.p2[std::abs(a - b2)])) : p2_constant;
    };
    const VU8 p2_along = penalty(row[x], row[x - dx]);
    const VU8 p2_vertical = penalty(row[x], prev_row[x]);
    const VU8 p2_back = penalty(row[x], prev_row[x - dx]);
    const VU8 p2_fwd = penalty(row[x], prev_row[x + dx]);
    const int slot = i % kWinnerBatch;
    band_first[slot] = start;
    uint16_t* const sums_out = output == RowOutput::kStoreSums ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp
                                                               : batch_sums + slot * Dp;
    const uint16_t* const sums_in = add_stored ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp : nullptr;
    if (kVectors8 > 1 && shift_along != 0) {
      for (int j = 0; j < kVectors8; ++j) hn::Store(along[j], d8, along_buffer + j * kN8);
    }

    VU8 mins_along = sentinel_v, mins_vertical = sentinel_v, mins_back = sentinel_v, mins_fwd = sentinel_v;
    LaneWinners winners = noWinners();
    VU8 along_new[kVectors8], vertical_new[kVectors8], back_new[kVectors8], fwd_new[kVectors8];
    for (int j = 0; j < kVectors8; ++j) {
      const int k = j * kN8;
      VU8 cost = hn::Zero(d8);
      for (int plane = 0; plane < kPlanes; ++plane) {
        const VU8 left = hn::Set(d8, static_cast<uint8_t>(census >> (8 * plane)));
        cost = hn::Add(cost, hn::PopulationCount(hn::Xor(left, hn::LoadU(d8, census_right[plane] + census_base + k))));
      }
      if (border) {
        const auto beyond = limit < 0 ? hn::FirstN(d8, kN8)
                                      : hn::Gt(hn::Iota(d8, k), hn::Set(d8, static_cast<uint8_t>(limit)));
        cost = hn::IfThenElse(beyond, worst_cost, cost);
      }
      auto step = [&](VU8 same, VU8 neighbours, VU8 p2)
                      HWY_ATTR { return hn::Add(cost, hn::Min(hn::Min(same, hn::Add(neighbours, p1)), p2)); };
      VU8 along_same, along_neighbours;
      if (shift_along == 0) {
        const VU8 before = j > 0 ? along[j - 1] : sentinel_v;
        const VU8 after = j + 1 < kVectors8 ? along[j + 1] : sentinel_v;
        along_same = along[j];
        along_neighbours = hn::Min(byteLanesFrom<kN8 - 1>(before, along[j]), byteLanesFrom<1>(along[j], after));
      } else if constexpr (kVectors8 == 1) {
        along_same = shiftedByteBand<0>(along[0], sentinel_v, shift_along);
        along_neighbours = hn::Min(shiftedByteBand<-1>(along[0], sentinel_v, shift_along),
                                   shiftedByteBand<1>(along[0], sentinel_v, shift_along));
      } else {
        const uint8_t* a = along_buffer + shift_along + k;
        along_same = hn::LoadU(d8, a);
        along_neighbours = byteNeighbourMin(a);
      }
      const VU8 l0 = step(along_same, along_neighbours, p2_along);
      const VU8 l1 = step(hn::LoadU(d8, vertical_in + k), byteNeighbourMin(vertical_in + k), p2_vertical);
      const VU8 l2 = step(hn::LoadU(d8, back + k), byteNeighbourMin(back + k), p2_back);
      const VU8 l3 = step(hn::LoadU(d8, fwd + k), byteNeighbourMin(fwd + k), p2_fwd);
      along_new[j] = l0;
      vertical_new[j] = l1;
      back_new[j] = l2;
      fwd_new[j] = l3;
      mins_along = hn::Min(mins_along, l0);
      mins_vertical = hn::Min(mins_vertical, l1);
      mins_back = hn::Min(mins_back, l2);
      mins_fwd = hn::Min(mins_fwd, l3);
      // The four paths' sum fits a byte (bandFitsBytes()); widened, it is the 16-bit kernel's.
      const VU8 sum8 = hn::Add(hn::Add(l0, l1), hn::Add(l2, l3));
      VU16 sum16[kN8 / kN16];
      widenBytes(d16, sum8, sum16);
      for (int h = 0; h < kN8 / kN16; ++h) {
        const int k16 = k + h * kN16;
        VU16 sum = sum16[h];
        if (sums_in) sum = hn::Add(sum, hn::Load(d16, sums_in + k16));
        hn::Store(sum, d16, sums_out + k16);
        if constexpr (kVectors16 > 1) winners.add(sum, hn::Load(d16, iota + k16));
      }
    }
    const VU8 along_min = byteMinBroadcast(mins_along);
    const VU8 vertical_min = byteMinBroadcast(mins_vertical);
    const VU8 back_min = byteMinBroadcast(mins_back), fwd_min = byteMinBroadcast(mins_fwd);
    for (int j = 0; j < kVectors8; ++j) {
      along[j] = hn::Sub(along_new[j], along_min);
      hn::Store(hn::Sub(vertical_new[j], vertical_min), d8, vertical + j * kN8);
      hn::Store(hn::Sub(back_new[j], back_min), d8, back_out + j * kN8);
      hn::Store(hn::Sub(fwd_new[j], fwd_min), d8, fwd_out + j * kN8);
    }
    if (output == RowOutput::kWinner) {
      if (p.lr_check) updateRightMinimum(p, b, x, sums_out, dx, start, kB);
      if constexpr (kVectors16 > 1) winners.store(b, slot);
      if (slot == kWinnerBatch - 1 || i == W - 1) {
        flushWinnerBatch(p, b, i, slot, dx, kN16, band_first, kB, kB, false, disparity, confidence);
      }
    }
  }
  finishRow(p, b, output, disparity, confidence);
}
