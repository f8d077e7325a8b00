#include "io/image/rle_deflate.h"

#include <gtest/gtest.h>
#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

namespace cenote::io {
namespace {

// Inflates a zlib stream with libdeflate and with zlib itself (the reference decoder, stricter
// about incomplete Huffman codes), both checking the Adler-32; `expected_size` exactly. Returns
// libdeflate's output after checking that zlib's is the same.
std::vector<uint8_t> inflate(const std::vector<uint8_t>& stream, std::size_t expected_size) {
  libdeflate_decompressor* d = libdeflate_alloc_decompressor();
  std::vector<uint8_t> out(expected_size);
  const libdeflate_result result = libdeflate_zlib_decompress(d, stream.data(), stream.size(), out.data(), out.size(),
                                                              nullptr);
  libdeflate_free_decompressor(d);
  EXPECT_EQ(result, LIBDEFLATE_SUCCESS) << "stream of " << stream.size() << " bytes";
  std::vector<uint8_t> by_zlib(expected_size + 1);  // one spare byte: a longer output shows
  uLongf zlib_size = by_zlib.size();
  EXPECT_EQ(uncompress(by_zlib.data(), &zlib_size, stream.data(), stream.size()), Z_OK)
      << "zlib refuses the stream of " << stream.size() << " bytes";
  by_zlib.resize(zlib_size);
  EXPECT_EQ(by_zlib, out) << "zlib and libdeflate disagree";
  return out;
}

void expectRoundTrip(const std::vector<uint8_t>& data, const std::string& what) {
  std::vector<uint8_t> stream = {0xAB};  // appends: what is there stays
  deflateRle(data.data(), data.size(), stream);
  ASSERT_EQ(stream[0], 0xAB) << what;
  stream.erase(stream.begin());
  EXPECT_EQ(inflate(stream, data.size()), data) << what;
}

TEST(RleDeflate, EmptyAndOneByteInputsRoundTrip) {
  expectRoundTrip({}, "empty");
  expectRoundTrip({0}, "one zero");
  expectRoundTrip({255}, "one 255");
  expectRoundTrip({7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7}, "eleven equal bytes");
}

TEST(RleDeflate, RunsOfEveryLengthAcrossBlocksRoundTrip) {
  // Runs of 1 to 600 bytes (longer than a match of 258, and crossing the 64 KB block borders).
  std::vector<uint8_t> data;
  for (int length = 1; length <= 600; ++length) data.insert(data.end(), static_cast<std::size_t>(length), length % 7);
  ASSERT_GT(data.size(), 2u * 64 * 1024);
  expectRoundTrip(data, "runs");
  expectRoundTrip(std::vector<uint8_t>(300000, 0), "one long run");
}

TEST(RleDeflate, RandomBytesRoundTripAndStayNearTheirSize) {
  std::mt19937 rng(5);
  std::vector<uint8_t> data(200001);
  for (uint8_t& b : data) b = static_cast<uint8_t>(rng());
  std::vector<uint8_t> stream;
  deflateRle(data.data(), data.size(), stream);
  EXPECT_EQ(inflate(stream, data.size()), data);
  EXPECT_LT(stream.size(), data.size() * 1.01) << "incompressible data grows by headers only";
}

TEST(RleDeflate, SkewedFrequenciesNeedingCodesLongerThan15BitsRoundTrip) {
  // Fibonacci frequencies: an unlimited Huffman code would give the rarest symbols ~22 bits.
  std::vector<uint8_t> data;
  uint32_t a = 1, b = 1;
  for (int symbol = 0; symbol < 22; ++symbol) {
    data.insert(data.end(), a, static_cast<uint8_t>(symbol * 11));
    const uint32_t next = a + b;
    a = b;
    b = next;
  }
  ASSERT_LE(data.size(), 64u * 1024) << "one block";
  std::shuffle(data.begin(), data.end(), std::mt19937(9));
  expectRoundTrip(data, "Fibonacci frequencies");
}

TEST(RleDeflate, SameInputGivesTheSameBytes) {
  std::vector<uint8_t> data(100000);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>((i * i) >> 7);
  std::vector<uint8_t> first, second;
  deflateRle(data.data(), data.size(), first);
  deflateRle(data.data(), data.size(), second);
  EXPECT_EQ(first, second);
}

}  // namespace
}  // namespace cenote::io
