#include "io/bag/lz4_frame.h"

#include <lz4frame.h>

#include "common/error.h"
#include "io/bag/output_growth.h"

namespace cenote::io::detail {

bool lz4FrameDecompress(std::span<const std::uint8_t> in, std::uint64_t declared, std::uint64_t max_bytes,
                        std::vector<std::uint8_t>& out, std::string& error) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) throw IoError("lz4: decoder failed to start");
  out.resize(initialOutputBytes(declared, in.size(), max_bytes));
  std::size_t consumed = 0, produced = 0;
  std::size_t hint = 1;  // 0 once the frame has ended
  while (hint != 0 && consumed < in.size()) {
    // A full buffer at max_bytes is still offered: LZ4 may end the frame without writing more.
    if (produced == out.size() && out.size() < max_bytes) out.resize(grownOutputBytes(out.size(), max_bytes));
    std::size_t src = in.size() - consumed, dst = out.size() - produced;
    hint = LZ4F_decompress(ctx, out.data() + produced, &dst, in.data() + consumed, &src, nullptr);
    if (LZ4F_isError(hint)) {
      error = LZ4F_getErrorName(hint);
      break;
    }
    consumed += src;
    produced += dst;
    if (src == 0 && dst == 0) break;  // no progress: the output is full
  }
  LZ4F_freeDecompressionContext(ctx);
  out.resize(produced);
  return error.empty() && hint == 0;
}

}  // namespace cenote::io::detail
