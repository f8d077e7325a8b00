// sgm_cost-inl.h: the SGM engine's matching cost, built on the fly for each pixel as a row is swept
// (SAD: reversed right rows, window rows of absolute differences in a ring, column sums and a
// running window sum; census: the right row's descriptors reversed): beginCostRow() and the column
// helpers the row kernels call. Compiled once per instruction set as part of sgm_engine.cpp, which
// includes it inside its Highway namespace after StripBuffers: not a standalone header.
// No include guard: sgm_engine.cpp is compiled once per target (hwy/foreach_target.h) and includes
// this file each time.

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
