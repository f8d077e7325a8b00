// zstd_block.h: one buffer in, one zstd frame out, and back, for data compressed on a hot path:
// the map's frame store packs about 3 MB of points for every integrated frame
// (mapping/history/frame_codec.h). On those bytes zstd's level 1 takes 2.8 ms for 1.30 MB where
// libdeflate's level 1 took 16.6 ms for 1.22 MB and ISA-L's igzip 6.8 ms for 1.94 MB; zstd
// decompresses them faster than igzip inflates its stream.
// Frames without their content size (zstd's streaming writer may leave it out) are refused.
// The frames are plain zstd frames with their content size and checksum, which any zstd reads.
// Threads: any thread; each keeps one compression and one decompression context between calls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace cenote::io {

inline constexpr int kZstdFastLevel = 1;  // the frame store's level: see above

// Appends the zstd frame of `in` at `level` (zstd's: negative is faster, up to 19; zstd clamps
// others) to `out`.
// @throws cenote::Error when zstd fails; ResourceExhaustedError when its context cannot be made.
void zstdCompressAppend(std::span<const uint8_t> in, int level, std::string& out);

// Decompresses the zstd frame `in` into exactly `out_size` bytes at `out`; false for a damaged
// frame (its checksum), or one that holds fewer or more bytes.
bool zstdDecompressExactly(std::span<const uint8_t> in, uint8_t* out, std::size_t out_size);

}  // namespace cenote::io
