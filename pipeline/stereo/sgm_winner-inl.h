// sgm_winner-inl.h: the SGM engine's winner search and left-right check: each pixel's smallest
// path sum lane by lane (LaneWinners), the winner and PKRN second minimum of a batch of pixels
// (pickWinner, flushWinnerBatch), their disparities, sub-pixel offsets and confidences
// (finishWinners), the right image's best sums (updateRightMinimum) and the check itself
// (leftRightCheck). Compiled once per instruction set as part of sgm_engine.cpp, which includes it
// inside its Highway namespace after StripBuffers and the lane helpers: not a standalone header.
// No include guard: sgm_engine.cpp is compiled once per target (hwy/foreach_target.h) and includes
// this file each time.

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

// One pixel's winner (its index from the sums' first disparity), smallest sum c1 and second
// smallest c2 outside the winner's span of `reach` disparities on either side, from its lane-wise
// search (`lanes`, vectors of N lanes, Dp sums).
struct PixelWinner {
  int winner;
  uint16_t c1, c2;
};

HWY_INLINE PixelWinner winnerOf(const LaneWinners& lanes, int N, int Dp, int reach) {
  const DU16 d;
  const VU16 best = lanes.best, best_index = lanes.best_index;
#if HWY_TARGET <= HWY_AVX3
  if (Dp == 32 && N == 32) {
    // One vector (the band on AVX-512): the smallest sum in every lane, its first lane from the
    // comparison's mask bits, and the span around it masked with the same bits, without a trip
    // of the winner through a general register and back into a vector.
    const VU16 c1_lanes = minWordBroadcast(d, best);
    const uint32_t equal = _mm512_cmpeq_epi16_mask(best.raw, c1_lanes.raw);
    const uint32_t first_bit = equal & (0u - equal);
    const uint32_t near = reach ? first_bit | (first_bit << 1) | (first_bit >> 1) : first_bit;
    const VU16 outside{_mm512_mask_mov_epi16(best.raw, near, _mm512_set1_epi16(static_cast<int16_t>(kNoCost)))};
    return {__builtin_ctz(equal), static_cast<uint16_t>(_mm_cvtsi128_si32(_mm512_castsi512_si128(c1_lanes.raw))),
            minLane(d, outside)};
  }
#endif
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
  const VU16 first_near = hn::Set(d, static_cast<uint16_t>(winner - reach));
  const VU16 span = hn::Set(d, static_cast<uint16_t>(2 * reach + 1));
  const auto best_is_near = hn::Lt(hn::Sub(best_index, first_near), span);
  return {winner, c1, minLane(d, hn::IfThenElse(best_is_near, lanes.second_best, best))};
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
  const PixelWinner w = winnerOf(lanes, N, Dp, p.pkrn_exclude_neighbours ? 1 : 0);
  out.winner[j] = first + w.winner;
  out.c1[j] = w.c1;
  out.c2[j] = w.c2;
  const bool subpixel = p.subpixel && w.winner > 0 && w.winner + 1 < valid;
  out.below[j] = subpixel ? s[w.winner - 1] : w.c1;
  out.above[j] = subpixel ? s[w.winner + 1] : w.c1;
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
