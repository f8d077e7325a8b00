// igzip_inflate.h: inflating a whole deflate stream of known size with ISA-L's igzip, about 1.6x
// libdeflate's speed on PNG frames (io/image/png_decoder.h). In the library cenote_compression,
// beside the frame store's zstd frames (zstd_block.h).
// Threads: any thread; each keeps one inflate state (87 KB) between calls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace cenote::io {

enum class DeflateWrapper { kRaw, kZlib };  // kZlib: the zlib header and its Adler-32, checked

// Inflates `in` into exactly `out_size` bytes at `out`; false for a damaged stream (a wrong
// Adler-32 with kZlib) or one that holds fewer or more bytes.
bool inflateExactly(std::span<const uint8_t> in, uint8_t* out, std::size_t out_size, DeflateWrapper wrapper);

}  // namespace cenote::io
