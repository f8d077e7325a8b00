// sgm_band_bytes-inl.h: what the band kernel (aggregateRowBand(), sgm_band-inl.h) needs to run in
// byte lanes, for census costs whose path costs fit in a byte: the test, the census descriptors in
// byte planes, and the widening of the four paths' sums. Compiled once per instruction set as part
// of sgm_engine.cpp, which includes it inside its Highway namespace before sgm_band-inl.h: not a
// standalone header.
// No include guard: sgm_engine.cpp is compiled once per target (hwy/foreach_target.h) and includes
// this file each time.
//
// In bytes the recurrence, the sentinels and the layout are those of the 16-bit band, one byte per
// disparity instead of two: a band of 32 is one 256-bit vector where 16-bit lanes need two (AVX2)
// or one of 512 bits (AVX-512), so every path step costs half the vector work. It is exact, not an
// approximation: bandFitsBytes() admits only parameters for which no value the recurrence forms
// exceeds 255 (census 5x5 at the default penalties: path costs at most 24 + 30, sentinels 94, sums
// of four paths at most 216), so every byte holds the number the 16-bit lane would, and the sums,
// widened to 16 bits, go through the same winner search and LR check.

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
