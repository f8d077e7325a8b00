#include "io/compression/zstd_block.h"

#include <zstd.h>

#include <memory>
#include <vector>

#include "common/error.h"

namespace cenote::io {
namespace {

struct CCtxFree {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct DCtxFree {
  void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};

}  // namespace

void zstdCompressAppend(std::span<const uint8_t> in, int level, std::string& out) {
  // One context per thread, kept between calls: zstd allocates its tables once.
  thread_local const std::unique_ptr<ZSTD_CCtx, CCtxFree> context(ZSTD_createCCtx());
  if (!context) throw ResourceExhaustedError("zstd: cannot allocate a compression context");
  // Compressed into a buffer the thread keeps, then appended: growing `out` by the bound first would
  // zero-fill about 3 MB for every frame the store packs, to keep 1.3 MB of it.
  thread_local std::vector<uint8_t> frame;
  const size_t bound = ZSTD_compressBound(in.size());
  if (frame.size() < bound) frame.resize(bound);
  // The frame's checksum (XXH64, 4 bytes) makes damaged bytes an error instead of other bytes.
  ZSTD_CCtx_setParameter(context.get(), ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(context.get(), ZSTD_c_checksumFlag, 1);
  const size_t n = ZSTD_compress2(context.get(), frame.data(), bound, in.data(), in.size());
  if (ZSTD_isError(n)) {
    throw Error("zstd: compressing " + std::to_string(in.size()) + " bytes at level " + std::to_string(level) +
                " failed: " + ZSTD_getErrorName(n));
  }
  out.append(reinterpret_cast<const char*>(frame.data()), n);
}

bool zstdDecompressExactly(std::span<const uint8_t> in, uint8_t* out, std::size_t out_size) {
  thread_local const std::unique_ptr<ZSTD_DCtx, DCtxFree> context(ZSTD_createDCtx());
  if (!context) throw ResourceExhaustedError("zstd: cannot allocate a decompression context");
  // A frame that declares another size is refused before any work; one that holds more than it
  // declares ends in an error (the output is full), one that holds less returns its short size.
  if (ZSTD_getFrameContentSize(in.data(), in.size()) != out_size) return false;
  const size_t n = ZSTD_decompressDCtx(context.get(), out, out_size, in.data(), in.size());
  return !ZSTD_isError(n) && n == out_size;
}

}  // namespace cenote::io
