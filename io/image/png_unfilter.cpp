// png_unfilter.cpp: Highway implementation of png_unfilter.h. Sixteen bytes at a time: their
// prefix sums with a stride of 3 bytes (three shifted adds), plus the last three bytes of the
// previous sixteen, the same byte k mod 3 of them for byte k (one table lookup): each block waits
// only on the lookup and add of the block before.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "io/image/png_unfilter.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include "io/image/png_unfilter.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::io::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The filter's definition, for the bytes after the last whole block.
void unfilterTail(const uint8_t* in, uint8_t* out, std::size_t from, std::size_t length) {
  for (std::size_t i = from; i < length; ++i) out[i] = static_cast<uint8_t>(in[i] + (i >= 3 ? out[i - 3] : 0));
}

void UnfilterSubRgbImpl(const uint8_t* in, uint8_t* out, std::size_t length) {
#if HWY_TARGET == HWY_SCALAR
  unfilterTail(in, out, 0, length);  // one lane: no blocks
#else
  const hn::Full128<uint8_t> d;
  // Byte k of a block takes the previous block's byte 13 + k mod 3: out[i - 3] of its channel.
  alignas(16) static constexpr uint8_t kCarry[16] = {13, 14, 15, 13, 14, 15, 13, 14, 15, 13, 14, 15, 13, 14, 15, 13};
  const hn::Vec<decltype(d)> carry_from = hn::Load(d, kCarry);
  hn::Vec<decltype(d)> previous = hn::Zero(d);  // the bytes before the row count as 0
  std::size_t i = 0;
  for (; i + 16 <= length; i += 16) {
    hn::Vec<decltype(d)> v = hn::LoadU(d, in + i);
    v = hn::Add(v, hn::ShiftLeftBytes<3>(d, v));
    v = hn::Add(v, hn::ShiftLeftBytes<6>(d, v));
    v = hn::Add(v, hn::ShiftLeftBytes<12>(d, v));
    v = hn::Add(v, hn::TableLookupBytes(previous, carry_from));
    hn::StoreU(v, d, out + i);
    previous = v;
  }
  unfilterTail(in, out, i, length);
#endif
}

}  // namespace HWY_NAMESPACE
}  // namespace cenote::io::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::io::detail {

HWY_EXPORT(UnfilterSubRgbImpl);

void unfilterSubRgb(const uint8_t* in, uint8_t* out, std::size_t length) {
  HWY_DYNAMIC_DISPATCH(UnfilterSubRgbImpl)(in, out, length);
}

}  // namespace cenote::io::detail
#endif
