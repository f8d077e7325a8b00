// lz4_frame.h: one LZ4 frame decoded as the readers of ROS 1 bags and MCAP files hold their chunks,
// its output grown as output_growth.h says rather than sized by the chunk's size field.
// Threads: free function.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cenote::io::detail {

/// Decodes the LZ4 frame `in` into `out` (resized to the bytes decoded), which grows from
/// initialOutputBytes(declared, ...) up to `max_bytes`. True when the frame ended; false when the data
/// ended first, the output reached `max_bytes`, or LZ4 rejected the data (`error` then holds its reason).
/// @throws IoError when LZ4 cannot make a decoder.
bool lz4FrameDecompress(std::span<const std::uint8_t> in, std::uint64_t declared, std::uint64_t max_bytes,
                        std::vector<std::uint8_t>& out, std::string& error);

}  // namespace cenote::io::detail
