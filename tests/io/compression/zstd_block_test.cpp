#include "io/compression/zstd_block.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <random>
#include <string>
#include <vector>

namespace cenote::io {
namespace {

std::vector<uint8_t> randomBytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> out(n);
  for (uint8_t& b : out) b = static_cast<uint8_t>(rng());
  return out;
}

// Like a frame's point section: small zigzag deltas, mostly one byte.
std::vector<uint8_t> deltaLikeBytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::geometric_distribution<int> small(0.4);
  std::vector<uint8_t> out(n);
  for (uint8_t& b : out) b = static_cast<uint8_t>(std::min(small(rng), 127));
  return out;
}

std::span<const uint8_t> bytesOf(const std::string& s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

const std::vector<std::vector<uint8_t>>& inputs() {
  static const std::vector<std::vector<uint8_t>> in = {
      {}, std::vector<uint8_t>(1, 42), std::vector<uint8_t>(1 << 20), randomBytes(300000, 1), deltaLikeBytes(2000000, 2)};
  return in;
}

TEST(ZstdBlock, FramesDecompressWithZstdsOwnDecoderToTheInputAndKeepWhatOutHeld) {
  for (int level : {kZstdFastLevel, -5, 3}) {
    for (size_t i = 0; i < inputs().size(); ++i) {
      const std::vector<uint8_t>& in = inputs()[i];
      std::string out = "prefix";
      zstdCompressAppend(in, level, out);
      ASSERT_EQ(out.substr(0, 6), "prefix") << "level " << level << ", input " << i;
      const std::string frame = out.substr(6);
      EXPECT_EQ(ZSTD_getFrameContentSize(frame.data(), frame.size()), in.size()) << "the frame declares its size";
      // RFC 8878: after the 4-byte magic, the frame header descriptor; its bit 2 is Content_Checksum_flag.
      ASSERT_GT(frame.size(), 4u);
      EXPECT_NE(static_cast<uint8_t>(frame[4]) & 0x04, 0) << "the frame carries its checksum";
      std::vector<uint8_t> back(in.size() + 1);  // one spare byte: a longer output shows
      const size_t n = ZSTD_decompress(back.data(), back.size(), frame.data(), frame.size());
      ASSERT_FALSE(ZSTD_isError(n)) << ZSTD_getErrorName(n) << ", level " << level << ", input " << i;
      back.resize(n);
      EXPECT_EQ(back, in) << "level " << level << ", input " << i;
    }
  }
}

TEST(ZstdBlock, DecompressesFramesOfZstdsOwnEncoderExactly) {
  for (size_t i = 0; i < inputs().size(); ++i) {
    const std::vector<uint8_t>& in = inputs()[i];
    std::string frame(ZSTD_compressBound(in.size()), '\0');
    frame.resize(ZSTD_compress(frame.data(), frame.size(), in.data(), in.size(), 3));
    std::vector<uint8_t> back(in.size());
    EXPECT_TRUE(zstdDecompressExactly(bytesOf(frame), back.data(), back.size())) << "input " << i;
    EXPECT_EQ(back, in) << "input " << i;
  }
}

TEST(ZstdBlock, RefusesAWrongSizeACutFrameAndDamagedBytes) {
  const std::vector<uint8_t>& in = inputs()[4];
  std::string frame;
  zstdCompressAppend(in, kZstdFastLevel, frame);
  std::vector<uint8_t> out(in.size() + 1);
  EXPECT_FALSE(zstdDecompressExactly(bytesOf(frame), out.data(), in.size() + 1)) << "more room than the frame holds";
  EXPECT_FALSE(zstdDecompressExactly(bytesOf(frame), out.data(), in.size() - 1)) << "less room than the frame holds";
  EXPECT_FALSE(zstdDecompressExactly(bytesOf(frame.substr(0, frame.size() / 2)), out.data(), in.size())) << "cut";
  std::string damaged = frame;
  for (size_t i = 20; i < damaged.size(); i += 997) damaged[i] = static_cast<char>(~damaged[i]);
  EXPECT_FALSE(zstdDecompressExactly(bytesOf(damaged), out.data(), in.size())) << "damaged";
  const std::string garbage = "not a zstd frame at all";
  EXPECT_FALSE(zstdDecompressExactly(bytesOf(garbage), out.data(), in.size())) << "garbage";
}

TEST(ZstdBlock, CompressesAPointSectionsKindOfBytes) {
  const std::vector<uint8_t>& in = inputs()[4];
  std::string out;
  zstdCompressAppend(in, kZstdFastLevel, out);
  // About 2.4 bits of entropy a byte here (geometric, p = 0.4): a working coder gets under 40 %.
  EXPECT_LT(out.size(), in.size() * 40 / 100) << out.size() << " bytes for " << in.size();
}

}  // namespace
}  // namespace cenote::io
