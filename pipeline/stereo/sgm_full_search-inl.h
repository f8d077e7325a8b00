// sgm_full_search-inl.h: the SGM engine's full-search row kernel (aggregateRowFull): every pixel
// searches all disparities (more than kBandDisparities of them; a shorter range runs as one band,
// see MatchStripImpl), the matching cost built on the fly, the four paths advanced and summed,
// the winners taken in batches. Compiled once per instruction set as part of sgm_engine.cpp, which
// includes it inside its Highway namespace after the helpers it shares with the band search (cost
// columns, path resets, winners, LR check): not a standalone header.
// No include guard: sgm_engine.cpp is compiled once per target (hwy/foreach_target.h) and includes
// this file each time.

// After pixel x: the minima of its three stored paths (vertical, forward and backward diagonal),
// which the next row's pixels read for their P2 term, into rows b.path_min[0], [2] and [3].
HWY_INLINE void storePathMinima(uint16_t* min_vertical, uint16_t* min_fwd, uint16_t* min_back, int x, VU16 mins_vertical,
                                VU16 mins_fwd, VU16 mins_back) {
  const DU16 d;
  min_vertical[x + 1] = minLane(d, mins_vertical);
  min_fwd[x + 1] = minLane(d, mins_fwd);
  min_back[x + 1] = minLane(d, mins_back);
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
