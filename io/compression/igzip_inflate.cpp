#include "io/compression/igzip_inflate.h"

#include <isa-l/igzip_lib.h>

#include <memory>

namespace cenote::io {

bool inflateExactly(std::span<const uint8_t> in, uint8_t* out, std::size_t out_size, DeflateWrapper wrapper) {
  // One state per thread, kept between calls: it is 87 KB, too large for every thread's stack.
  thread_local const std::unique_ptr<inflate_state> state = std::make_unique<inflate_state>();
  isal_inflate_init(state.get());
  state->crc_flag = wrapper == DeflateWrapper::kZlib ? ISAL_ZLIB : ISAL_DEFLATE;
  state->next_in = const_cast<uint8_t*>(in.data());
  state->avail_in = static_cast<uint32_t>(in.size());
  state->next_out = out;
  state->avail_out = static_cast<uint32_t>(out_size);
  // A longer stream ends in ISAL_OUT_OVERFLOW, a shorter one leaves output space.
  return isal_inflate_stateless(state.get()) == ISAL_DECOMP_OK && state->avail_out == 0;
}

}  // namespace cenote::io
