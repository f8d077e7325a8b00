// sgm_band-inl.h: the coarse-to-fine band of the SGM engine (aggregateRowBand), compiled once per
// instruction set as part of sgm_engine.cpp, which includes it inside its Highway namespace after
// the helpers it shares with the full search (cost columns, path resets, winners, LR check; see
// sgm_cost-inl.h and sgm_winner-inl.h): not a standalone header. Every pixel searches
// kBandDisparities disparities from its own start.
// No include guard: sgm_engine.cpp is compiled once per target (hwy/foreach_target.h) and includes
// this file each time.

// Coarse-to-fine band: every pixel searches kBandDisparities disparities from its own start
// (SgmImages::band_start), so a path's predecessor may cover other disparities. Its costs are
// read at the current pixel's start, shifted by the difference of the two starts; the lanes of a
// path pixel past its band hold sentinels larger than any path cost plus P2 (so a disparity the
// predecessor did not search counts as infinite), and a shift beyond the band reads sentinels only.
// The band's path costs are stored less their minimum over the band, L'(p, d) = L(p, d) - min_k L(p, k)
// (the along path's too, in registers), so that the recurrence
//   L(p, d) = C(p, d) + min(L(p-r, d), L(p-r, d+-1) + P1, min_k L(p-r, k) + P2) - min_k L(p-r, k)
// reads C(p, d) + min(L'(p-r, d), L'(p-r, d+-1) + P1, P2): the same values bit for bit (every lane a
// pixel reads, sentinels included, is at least the pixel's minimum, so no difference wraps), without
// a row of minima per direction to store, read and broadcast for the next row (the full search keeps
// StripBuffers::path_min). The sums for the winner add the L themselves.

// Predecessor shift, clamped to where only sentinels are read (the d - 1 / d + 1 loads reach one
// lane further than the band on either side).
HWY_INLINE int bandShift(int start, int start_prev) {
  return std::clamp(start - start_prev, -(kBandDisparities + 1), kBandDisparities + 1);
}

// out[x] = bandShift(start[x], start_prev[x + offset]) for the x of [0, width) whose x + offset is in
// [0, width), 0 for the others (offset -1, 0 or 1): the shifts of one predecessor direction for a
// whole row, computed before its sweep instead of per pixel.
void bandShiftRow(const int16_t* start, const int16_t* start_prev, int offset, int width, int16_t* out) {
  const hn::ScalableTag<int16_t> d;
  const int N = static_cast<int>(hn::Lanes(d));
  const auto lo = hn::Set(d, static_cast<int16_t>(-(kBandDisparities + 1)));
  const auto hi = hn::Set(d, static_cast<int16_t>(kBandDisparities + 1));
  const int begin = std::max(0, -offset), end = std::min(width, width - offset);
  std::fill(out, out + begin, 0);
  std::fill(out + end, out + width, 0);
  int x = begin;
  for (; x + N <= end; x += N) {
    const auto shift = hn::Sub(hn::LoadU(d, start + x), hn::LoadU(d, start_prev + x + offset));
    hn::StoreU(hn::Min(hn::Max(shift, lo), hi), d, out + x);
  }
  for (; x < end; ++x) out[x] = static_cast<int16_t>(bandShift(start[x], start_prev[x + offset]));
}

// The predecessors' shifts of row y's pixels (StripBuffers::band_shift): along the row from x - dx
// (0 at the row's first pixel), and from the previous row at x, x - dx and x + dx (0 off the image
// and on the pass's first row, whose predecessors read zero costs at 0).
void bandShifts(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y, int dx, bool first_row) {
  const int16_t* starts = im.band_start + y * im.band_stride;
  bandShiftRow(starts, starts, -dx, p.width, b.band_shift[0]);
  if (first_row) {
    for (int k = 1; k < 4; ++k) std::fill(b.band_shift[k], b.band_shift[k] + p.width, 0);
    return;
  }
  const int16_t* prev_starts = im.band_start + (y - dx) * im.band_stride;
  bandShiftRow(starts, prev_starts, 0, p.width, b.band_shift[1]);
  bandShiftRow(starts, prev_starts, -dx, p.width, b.band_shift[2]);
  bandShiftRow(starts, prev_starts, dx, p.width, b.band_shift[3]);
}

// The along-row path starts fresh at the first pixel of every row: zero costs in the band (lanes
// of type T: 16 bits or bytes).
template <class T>
void resetAlongBand(const StripBuffers& b, T sentinel) {
  for (T* pixel : {reinterpret_cast<T*>(b.along[0]), reinterpret_cast<T*>(b.along[1])}) {
    std::fill(pixel, pixel + 5 * kBandDisparities, sentinel);
    std::fill(pixel + 2 * kBandDisparities, pixel + 3 * kBandDisparities, T{0});
  }
}

// The band of the previous pixel on the row (`prev`, lanes past it sentinels) as seen from a
// band starting `shift` disparities later: lane i holds lane i + shift + kOffset of `prev`.
// In registers: the previous pixel's path was just computed, and reloading it from memory at
// another alignment would miss store-to-load forwarding.
template <int kOffset, class V>
HWY_INLINE V shiftedBand(V prev, V sentinel, int shift, const uint16_t* iota) {
  using T = hn::TFromV<V>;
  constexpr int kLanes = static_cast<int>(hn::MaxLanes(hn::DFromV<V>()));
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  if constexpr (kLanes == 32 && sizeof(T) == 2) {
    const __m512i index = _mm512_add_epi16(_mm512_load_si512(iota),
                                           _mm512_set1_epi16(static_cast<int16_t>(shift + kOffset)));
    // Lanes whose source index is outside [0, 32) (as unsigned) keep the sentinel.
    const __mmask32 inside = _mm512_cmplt_epu16_mask(index, _mm512_set1_epi16(32));
    return V{_mm512_mask_permutexvar_epi16(sentinel.raw, inside, index, prev.raw)};
  }
#endif
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3_DL
  if constexpr (kLanes == 32 && sizeof(T) == 1) {  // VBMI: bytes permuted across the whole vector
    const __m256i index = _mm256_add_epi8(hn::Iota(hn::DFromV<V>(), 0).raw,
                                          _mm256_set1_epi8(static_cast<char>(shift + kOffset)));
    const __mmask32 inside = _mm256_cmplt_epu8_mask(index, _mm256_set1_epi8(32));
    return V{_mm256_mask_permutexvar_epi8(sentinel.raw, inside, index, prev.raw)};
  }
#endif
  (void)iota;
  const hn::DFromV<V> d;
  HWY_ALIGN T lanes[3 * kLanes];
  hn::Store(sentinel, d, lanes);
  hn::Store(prev, d, lanes + kLanes);
  hn::Store(sentinel, d, lanes + 2 * kLanes);
  const int at = std::clamp(shift + kOffset, -kLanes, kLanes);
  return hn::LoadU(d, lanes + kLanes + at);
}

// A band's path row pixel x (lanes of type T): the rows' memory holds the band's layout (lead
// 2 kBandDisparities, stride 3 kBandDisparities) counted in T.
template <class T>
HWY_INLINE T* bandPathPixel(uint16_t* row, int x) {
  constexpr int kStride = 3 * kBandDisparities, kLead = 2 * kBandDisparities;
  return reinterpret_cast<T*>(row) + kLead + static_cast<std::ptrdiff_t>(x + 1) * kStride;
}

// The four paths' sums of the pixel's vector k of path costs (plus the first pass's sums when
// `sums_in`), stored as 16 bits in `sums_out`; fed to `winners` when the band takes several 16-bit
// vectors (flushWinnerBatch() takes one from the sums). Byte lanes: summed in bytes (they fit,
// bandFitsBytes()), then widened.
template <class V>
HWY_INLINE void storeBandSums(V l0, V l1, V l2, V l3, const uint16_t* sums_in, uint16_t* sums_out, int k,
                              const uint16_t* iota, LaneWinners& winners) {
  const DU16 d16;
  constexpr int kN16 = static_cast<int>(hn::MaxLanes(DU16()));
  constexpr bool kFeedWinners = kBandDisparities > kN16;
  if constexpr (sizeof(hn::TFromV<V>) == 2) {
    const VU16 sum = storePathSum(l0, l1, l2, l3, sums_in, sums_out, k);
    if constexpr (kFeedWinners) winners.add(sum, hn::Load(d16, iota + k));
  } else {
    constexpr int kParts = static_cast<int>(hn::MaxLanes(hn::DFromV<V>())) / kN16;
    static_assert(kParts == 1 || kParts == 2, "widenBytes() gives one or two 16-bit vectors");
    VU16 sums[kParts];
    widenBytes(d16, hn::Add(hn::Add(l0, l1), hn::Add(l2, l3)), sums);
    for (int h = 0; h < kParts; ++h) {
      const int k16 = k + h * kN16;
      if (sums_in) sums[h] = hn::Add(sums[h], hn::Load(d16, sums_in + k16));
      hn::Store(sums[h], d16, sums_out + k16);
      if constexpr (kFeedWinners) winners.add(sums[h], hn::Load(d16, iota + k16));
    }
  }
}

// Band SAD. The full search keeps running column sums over the whole range; here each pixel
// sums its window's columns over its own band only, the columns' sums over the window rows
// computed from the window's right rows (kept reversed and widened to 16 bits). The pixels of a
// 4x4 block share their band (StereoConfig::coarse_scale), so a pixel usually takes the previous
// pixel's columns, in registers, and computes only the one entering its window.

// The window's right rows around row y: all of them at the first row of a pass, else the one
// entering the window along dy (ring slot by image row, as the full search's column ring).
template <int kWindow>
void beginBandSadRow(const SgmParams& p, const SgmImages& im, const StripBuffers& b, int y, int dy, bool first_row) {
  constexpr int r = kWindow / 2;
  const int first = first_row ? y - r : y + dy * r;
  const int last = first_row ? y + r : first;
  for (int yy = first; yy <= last; ++yy) {
    const std::ptrdiff_t at = clampRow(yy, p.height) * im.image_stride;
    const int slot = ringSlot(yy, kWindow);
    reverseRow(im.right + at, p.width, b.reversed_length,
               b.band_rows + static_cast<std::ptrdiff_t>(slot) * b.reversed_length);
    std::copy_n(im.left + at, p.width, b.band_left_rows + static_cast<std::ptrdiff_t>(slot) * p.width);
  }
}

// The rows of the window around row y, widened (the ring of beginBandSadRow()): left as the cost
// compares them, right reversed. Widened, a left pixel is broadcast straight from memory.
template <int kWindow>
struct BandSadWindow {
  const int16_t* left[kWindow];
  const int16_t* right[kWindow];
};

template <int kWindow>
BandSadWindow<kWindow> bandSadWindow(const SgmParams& p, const StripBuffers& b, int y) {
  BandSadWindow<kWindow> w;
  for (int i = 0; i < kWindow; ++i) {
    const int yy = y - kWindow / 2 + i;
    w.left[i] = reinterpret_cast<const int16_t*>(b.band_left_rows) + ringSlot(yy, kWindow) * p.width;
    w.right[i] = reinterpret_cast<const int16_t*>(b.band_rows) + ringSlot(yy, kWindow) * b.reversed_length;
  }
  return w;
}

// Sums over the window rows of |left - right| at column c (clamped to the image), for the band
// from `start`: kVectors vectors.
template <int kWindow, int kVectors>
HWY_INLINE void bandColumn(const SgmParams& p, const BandSadWindow<kWindow>& window, int c, int start,
                           VU16 (&out)[kVectors]) {
  const DU16 d;
  const hn::RebindToSigned<DU16> di;
  constexpr int kN = static_cast<int>(hn::MaxLanes(DU16()));
  c = clampColumn(c, p.width);
  const std::ptrdiff_t at = p.width - 1 - c + p.min_disparity + start;  // reversedAt()
  hn::Vec<decltype(di)> left[kWindow];
  for (int i = 0; i < kWindow; ++i) left[i] = hn::Set(di, window.left[i][c]);
  for (int j = 0; j < kVectors; ++j) {
    auto sum = hn::Abs(hn::Sub(left[0], hn::LoadU(di, window.right[0] + at + j * kN)));
    for (int i = 1; i < kWindow; ++i) {
      sum = hn::Add(sum, hn::Abs(hn::Sub(left[i], hn::LoadU(di, window.right[i] + at + j * kN))));
    }
    out[j] = hn::BitCast(d, sum);
  }
}

// One row of one pass, as aggregateRowFull(), over each pixel's band. kWindow: the SAD window
// side, 0 for census. DP: the path costs' lanes, DU16, or DU8 for census costs that fit a byte
// (bandFitsBytes(); kPlanes: censusBytePlanes()), which give the same sums bit for bit.
template <int kWindow, class DP, int kPlanes = 0>
void aggregateRowBand(const SgmParams& p, const SgmImages& im, StripBuffers& b, const PenaltyTable& pen, int y, int dx,
                      bool first_row, RowOutput output, uint16_t* stored_sums, bool add_stored, float* disparity,
                      float* confidence) {
  using T = hn::TFromD<DP>;
  using V = hn::Vec<DP>;
  const DP d;
  constexpr bool kCensus = kWindow == 0;
  constexpr bool kBytes = sizeof(T) == 1;
  static_assert(!kBytes || (kCensus && kPlanes > 0), "byte lanes are for census costs");
  constexpr int kN = static_cast<int>(hn::MaxLanes(DP()));
  constexpr int kN16 = static_cast<int>(hn::MaxLanes(DU16()));
  constexpr int kB = kBandDisparities;
  constexpr int kVectors = kB / kN;
  static_assert(kB % kN == 0 && kB % kN16 == 0, "the band must be a whole number of vectors");
  const int Dp = b.padded, W = p.width;
  constexpr int r = kWindow / 2;
  const V p1 = hn::Set(d, static_cast<T>(p.p1));
  const T sentinel = static_cast<T>(pathSentinel(p, true));
  const V sentinel_v = hn::Set(d, sentinel);
  const V worst_cost = hn::Set(d, static_cast<T>(p.max_cost));
  // Fewer than kB disparities (a full search in one band starting at 0, MatchStripImpl): the lanes
  // past D hold the full search's sentinel, as its path rows do.
  const int searched = std::min(kB, p.num_disparities);
  const V beyond_range = hn::Set(d, static_cast<T>(pathSentinel(p, false)));
  const uint8_t* row = im.guide + y * im.image_stride;
  const uint8_t* prev_row = im.guide + (y - dx) * im.image_stride;  // inside the image border
  const int16_t* starts = im.band_start + y * im.band_stride;
  bandShifts(p, im, b, y, dx, first_row);
  const int16_t* const shifts_along = b.band_shift[0];
  const int16_t* const shifts_vertical = b.band_shift[1];
  const int16_t* const shifts_back = b.band_shift[2];
  const int16_t* const shifts_fwd = b.band_shift[3];
  if constexpr (kBytes) {
    beginCensusByteRow(p, im, b, y);
  } else if constexpr (kCensus) {
    beginCostRow(p, im, b, y, dx, dx, first_row);  // the right row's descriptors, reversed
  } else {
    beginBandSadRow<kWindow>(p, im, b, y, dx, first_row);
  }
  const uint32_t* const census_left = im.census_left ? im.census_left + clampRow(y, p.height) * im.census_stride : nullptr;
  if (output == RowOutput::kWinner && p.lr_check) {
    std::fill(b.right_min, b.right_min + b.reversed_length, kNoCost);
    std::fill(b.right_arg, b.right_arg + b.reversed_length, 0);
  }
  resetAlongBand(b, sentinel);
  T* const along_buffer = reinterpret_cast<T*>(b.along[0]) + 2 * kB;  // the previous pixel's along path, when shifted
  V along[kVectors];
  for (int j = 0; j < kVectors; ++j) along[j] = hn::Zero(d);
  HWY_ALIGN int32_t band_first[kWinnerBatch];
  // Everything the pixel loop reads, in locals: Highway's stores may alias anything, and the
  // compiler would otherwise reload struct fields after every store.
  constexpr int kStride = 3 * kB;  // StripBuffers::pixel_stride of the band
  T* const path_vertical = bandPathPixel<T>(b.path[0], 0);
  const T* const path_back = bandPathPixel<T>(b.path[1], 0);
  T* const path_back_out = bandPathPixel<T>(b.path[3], 0);
  T* const path_fwd = bandPathPixel<T>(b.path[2], 0);
  const uint16_t* const iota = b.iota;
  // Band SAD: the window's column sums at the band of the pixel that computed them (columns
  // x - r dx .. x + r dx, the last one entering the window), and that band's start.
  constexpr int kColumns = kCensus ? 1 : kWindow;
  VU16 columns[kColumns][kB / kN16];
  int columns_start = -1;
  BandSadWindow<kCensus ? 1 : kWindow> window{};
  if constexpr (!kCensus) window = bandSadWindow<kWindow>(p, b, y);
  uint16_t* const batch_sums = b.sums;
  const uint16_t* const census_right_lo = b.census_reversed[0];
  const uint16_t* const census_right_hi = b.census_reversed[1];
  const uint8_t* const census_right_bytes[3] = {b.census_bytes[0], b.census_bytes[1], b.census_bytes[2]};
  const int sad_shift = p.sad_shift;
  const bool adaptive = p.adaptive_p2;
  const V p2_constant = hn::Set(d, static_cast<T>(p.p2));
  for (int i = 0; i < W; ++i) {
    const int x = dx > 0 ? i : W - 1 - i;
    const int start = starts[x];
    const int shift_along = shifts_along[x], shift_vertical = shifts_vertical[x];
    const int shift_back = shifts_back[x], shift_fwd = shifts_fwd[x];

    if constexpr (!kCensus) {
      if (start == columns_start) {  // the previous pixel's band: its columns, one further
        for (int c = 0; c + 1 < kWindow; ++c) {
          for (int j = 0; j < kVectors; ++j) columns[c][j] = columns[c + 1][j];
        }
        bandColumn<kWindow>(p, window, x + dx * r, start, columns[kWindow - 1]);
      } else {
        for (int c = 0; c < kWindow; ++c) bandColumn<kWindow>(p, window, x + dx * (c - r), start, columns[c]);
        columns_start = start;
      }
    }
    // Lanes from `limit` + 1 on have no right pixel (start + lane > x - min_d): largest cost.
    const int limit = x - p.min_disparity - start;
    const bool border = limit < kB - 1;
    const uint32_t census = kCensus ? census_left[x] : 0;
    const std::ptrdiff_t census_base = W - 1 - x + p.min_disparity + start;

    T* const vertical = path_vertical + static_cast<std::ptrdiff_t>(x) * kStride;
    const T* const vertical_in = vertical + shift_vertical;
    const T* const back = path_back + static_cast<std::ptrdiff_t>(x - dx) * kStride + shift_back;
    T* const back_out = path_back_out + static_cast<std::ptrdiff_t>(x) * kStride;
    const T* const fwd = path_fwd + static_cast<std::ptrdiff_t>(x + dx) * kStride + shift_fwd;
    T* const fwd_out = path_fwd + static_cast<std::ptrdiff_t>(x) * kStride;
    // P2 per direction: one constant unless adapted to the intensity step.
    auto penalty = [&](uint8_t a, uint8_t b2)
                       HWY_ATTR { return adaptive ? hn::Set(d, static_cast<T>(pen.p2[std::abs(a - b2)])) : p2_constant; };
    const V p2_along = penalty(row[x], row[x - dx]);
    const V p2_vertical = penalty(row[x], prev_row[x]);
    const V p2_back = penalty(row[x], prev_row[x - dx]);
    const V p2_fwd = penalty(row[x], prev_row[x + dx]);
    const int slot = i % kWinnerBatch;
    band_first[slot] = start;
    uint16_t* const sums_out = output == RowOutput::kStoreSums ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp
                                                               : batch_sums + slot * Dp;
    const uint16_t* const sums_in = add_stored ? stored_sums + static_cast<std::ptrdiff_t>(x) * Dp : nullptr;
    // The along-row predecessor when it searched another band: one vector is shifted in
    // registers, several go through memory.
    if (kVectors > 1 && shift_along != 0) {
      for (int j = 0; j < kVectors; ++j) hn::Store(along[j], d, along_buffer + j * kN);
    }

    V mins_along = sentinel_v, mins_vertical = sentinel_v, mins_back = sentinel_v, mins_fwd = sentinel_v;
    LaneWinners winners = noWinners();
    V along_new[kVectors], vertical_new[kVectors], back_new[kVectors], fwd_new[kVectors];
    for (int j = 0; j < kVectors; ++j) {
      const int k = j * kN;
      V cost;
      if constexpr (kBytes) {
        // Hamming distance as the popcounts of the descriptors' bytes: a descriptor has
        // window^2 - 1 bits (CensusTransformImpl), all in its first kPlanes bytes.
        cost = hn::Zero(d);
        for (int plane = 0; plane < kPlanes; ++plane) {
          const V left = hn::Set(d, static_cast<T>(census >> (8 * plane)));
          cost = hn::Add(cost,
                         hn::PopulationCount(hn::Xor(left, hn::LoadU(d, census_right_bytes[plane] + census_base + k))));
        }
      } else if constexpr (kCensus) {
        const V lo = hn::Xor(hn::Set(d, static_cast<T>(census & 0xFFFF)), hn::LoadU(d, census_right_lo + census_base + k));
        const V hi = hn::Xor(hn::Set(d, static_cast<T>(census >> 16)), hn::LoadU(d, census_right_hi + census_base + k));
        cost = hn::Add(hn::PopulationCount(lo), hn::PopulationCount(hi));
      } else {
        VU16 acc = columns[0][j];
        for (int c = 1; c < kWindow; ++c) acc = hn::Add(acc, columns[c][j]);
        cost = hn::ShiftRightSame(acc, sad_shift);
      }
      if (border) {
        const auto beyond = limit < 0 ? hn::FirstN(d, kN)
                                      : hn::Gt(hn::Iota(d, static_cast<T>(k)), hn::Set(d, static_cast<T>(limit)));
        cost = hn::IfThenElse(beyond, worst_cost, cost);
      }
      // The predecessors are stored less their minimum (see above), so the jump from it costs P2.
      auto step = [&](V same, V neighbours, V p2)
                      HWY_ATTR { return hn::Add(cost, hn::Min(hn::Min(same, hn::Add(neighbours, p1)), p2)); };
      V along_same, along_neighbours;
      if (shift_along == 0) {
        const V before = j > 0 ? along[j - 1] : sentinel_v;
        const V after = j + 1 < kVectors ? along[j + 1] : sentinel_v;
        along_same = along[j];
        along_neighbours = hn::Min(shiftInPrevious(before, along[j]), shiftInNext(along[j], after));
      } else if constexpr (kVectors == 1) {
        along_same = shiftedBand<0>(along[0], sentinel_v, shift_along, iota);
        along_neighbours = hn::Min(shiftedBand<-1>(along[0], sentinel_v, shift_along, iota),
                                   shiftedBand<1>(along[0], sentinel_v, shift_along, iota));
      } else {
        const T* a = along_buffer + shift_along + k;
        along_same = hn::LoadU(d, a);
        along_neighbours = neighbourMin(a);
      }
      V l0 = step(along_same, along_neighbours, p2_along);
      // A predecessor of the same band in one 512-bit vector (16-bit lanes on AVX-512): aligned,
      // its lanes d -+ 1 beyond the band are sentinels, so its neighbours are shifted in registers
      // instead of loaded across cache lines (5 % of the CPU time there). Narrower vectors keep the
      // loads: the shifts cost more instructions than the loads they save (AVX2 bytes: 224.8 M
      // against 212.2 M a frame) and gain no time.
      constexpr bool kShiftAligned = kVectors == 1 && kN * sizeof(T) == 64;
      auto predecessor = [&](const T* at, int shift, V p2) HWY_ATTR {
        if (kShiftAligned && shift == 0) {
          const V same = hn::Load(d, at + k);  // k = 0
          return step(same, hn::Min(shiftInPrevious(sentinel_v, same), shiftInNext(same, sentinel_v)), p2);
        }
        return step(hn::LoadU(d, at + k), neighbourMin(at + k), p2);
      };
      V l1 = predecessor(vertical_in, shift_vertical, p2_vertical);
      V l2 = predecessor(back, shift_back, p2_back);
      V l3 = predecessor(fwd, shift_fwd, p2_fwd);
      if (searched < kB) {
        const auto in_range = hn::FirstN(d, static_cast<std::size_t>(std::clamp(searched - k, 0, kN)));
        l0 = hn::IfThenElse(in_range, l0, beyond_range);
        l1 = hn::IfThenElse(in_range, l1, beyond_range);
        l2 = hn::IfThenElse(in_range, l2, beyond_range);
        l3 = hn::IfThenElse(in_range, l3, beyond_range);
      }
      // Stored once their minima are known (the vertical path after every vector has read the
      // old values).
      along_new[j] = l0;
      vertical_new[j] = l1;
      back_new[j] = l2;
      fwd_new[j] = l3;
      if constexpr (kVectors == 1) {  // the path costs themselves (the along path waits for its minimum)
        mins_along = l0;
        mins_vertical = l1;
        mins_back = l2;
        mins_fwd = l3;
      } else {
        mins_along = hn::Min(mins_along, l0);
        mins_vertical = hn::Min(mins_vertical, l1);
        mins_back = hn::Min(mins_back, l2);
        mins_fwd = hn::Min(mins_fwd, l3);
      }
      storeBandSums(l0, l1, l2, l3, sums_in, sums_out, k, iota, winners);
    }
    const V along_min = minLaneBroadcast(d, mins_along);
    const V vertical_min = minLaneBroadcast(d, mins_vertical);
    const V back_min = minLaneBroadcast(d, mins_back), fwd_min = minLaneBroadcast(d, mins_fwd);
    for (int j = 0; j < kVectors; ++j) {
      along[j] = hn::Sub(along_new[j], along_min);
      hn::Store(hn::Sub(vertical_new[j], vertical_min), d, vertical + j * kN);
      hn::Store(hn::Sub(back_new[j], back_min), d, back_out + j * kN);
      hn::Store(hn::Sub(fwd_new[j], fwd_min), d, fwd_out + j * kN);
    }
    if (output == RowOutput::kWinner) {
      // The LR check's right-image minimum here, not in flushWinnerBatch(): there, each pixel's
      // load of the minima waited for the previous pixel's store of them, one element apart (a
      // partial overlap, which store-to-load forwarding cannot serve; 4 % of the CPU time on
      // AVX-512). A pixel's loop later, that store has left.
      if (p.lr_check) updateRightMinimum(p, b, x, sums_out, dx, start, kB);
      if constexpr (kB > kN16) winners.store(b, slot);
      if (slot == kWinnerBatch - 1 || i == W - 1) {
        flushWinnerBatch(p, b, i, slot, dx, kN16, band_first, searched, kB, false, disparity, confidence);
      }
    }
  }
  finishRow(p, b, output, disparity, confidence);
}
