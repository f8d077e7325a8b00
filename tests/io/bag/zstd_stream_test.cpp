// zstdDecompress (io/bag/zstd_stream.h) on frames of zstd's own compressor, with and without their
// content size, and on a frame header whose declared size its bytes cannot hold.
#include "io/bag/zstd_stream.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <zstd.h>

#include <cstdint>
#include <vector>

#include "common/error.h"

namespace cenote::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes compressed(const Bytes& in) {
  Bytes out(ZSTD_compressBound(in.size()));
  out.resize(ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1));
  return out;
}

// 4 MiB of zeros and a few bytes: far more than 64:1, decoded as a stream, not in one call.
TEST(ZstdStream, FrameThatCompressesFarDecodesWholeThroughTheStream) {
  Bytes in(std::size_t{4} << 20, 0);
  in[12345] = 7;
  in.back() = 9;
  const Bytes frame = compressed(in);
  ASSERT_GT(in.size(), 64 * frame.size());
  ASSERT_EQ(ZSTD_getFrameContentSize(frame.data(), frame.size()), in.size());
  Bytes out;
  zstdDecompress(frame, out);
  EXPECT_EQ(out, in);
  const Bytes small = {1, 2, 3, 4, 5, 6, 7, 8};
  zstdDecompress(compressed(small), out);
  EXPECT_EQ(out, small);
}

// A frame header that declares 1 GiB (single segment, 8-byte content size) and four bytes of block: the
// declared size is never allocated, and zstd's own error names the damage.
TEST(ZstdStream, DeclaredSizeTheBytesCannotHoldIsNotAllocated) {
  Bytes frame = {0x28, 0xb5, 0x2f, 0xfd, 0xe0};  // magic; descriptor: 8-byte content size, single segment
  const std::uint64_t declared = std::uint64_t{1} << 30;
  for (int i = 0; i < 8; ++i) frame.push_back(static_cast<std::uint8_t>(declared >> (8 * i)));
  frame.insert(frame.end(), {0x01, 0x00, 0x00, 0x42});  // a last raw block of 0 bytes, and one byte more
  ASSERT_EQ(ZSTD_getFrameContentSize(frame.data(), frame.size()), declared);
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  Bytes out;
  EXPECT_THAT([&] { zstdDecompress(frame, out); },
              testing::ThrowsMessage<IoError>("zstd: Frame requires too much memory for decoding"));
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024) << "peak resident KiB grew";
}

}  // namespace
}  // namespace cenote::io
