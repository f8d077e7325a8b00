// Headers, structure checks and strict decoding of PNG and JPEG files written by OpenCV (an
// independent writer), then cut, damaged or given sizes their data cannot hold.
#include "io/image/image_header.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "common/error.h"
#include "io/image/image_io.h"
#include "io/image/jpeg_decoder.h"

namespace cenote::io {
namespace {

using Bytes = std::vector<uint8_t>;

cv::Mat noise(int rows, int cols, int type, int seed) {
  cv::Mat m(rows, cols, type);
  cv::theRNG().state = static_cast<uint64_t>(seed);
  cv::randu(m, 0, (CV_MAT_DEPTH(type) == CV_16U) ? 65535 : 255);
  return m;
}

Bytes encode(const std::string& ext, const cv::Mat& image, const std::vector<int>& params = {}) {
  Bytes bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes, params)) << ext;
  return bytes;
}

void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

// The PNG with its IHDR claiming width x height, CRC recomputed (a well-formed lie).
Bytes withPngSize(Bytes png, uint32_t width, uint32_t height) {
  put32(png.data() + 16, width);
  put32(png.data() + 20, height);
  put32(png.data() + 29, static_cast<uint32_t>(crc32(0, png.data() + 12, 17)));
  return png;
}

// Offset of the first chunk of this type, or npos.
size_t findChunk(const Bytes& png, const char* type) {
  for (size_t pos = 8; pos + 12 <= png.size();) {
    const uint32_t length = (uint32_t{png[pos]} << 24) | (png[pos + 1] << 16) | (png[pos + 2] << 8) | png[pos + 3];
    if (std::memcmp(png.data() + pos + 4, type, 4) == 0) return pos;
    pos += 12 + length;
  }
  return std::string::npos;
}

void fixChunkCrc(Bytes& png, size_t pos) {
  const uint32_t length = (uint32_t{png[pos]} << 24) | (png[pos + 1] << 16) | (png[pos + 2] << 8) | png[pos + 3];
  put32(png.data() + pos + 8 + length, static_cast<uint32_t>(crc32(0, png.data() + pos + 4, length + 4)));
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST(ImageHeader, PngHeaderGivesSizeDepthAndChannels) {
  struct Case {
    int type, depth, channels;
  };
  for (const Case& c : {Case{CV_8UC1, 8, 1}, Case{CV_8UC3, 8, 3}, Case{CV_8UC4, 8, 4}, Case{CV_16UC1, 16, 1}}) {
    const Bytes png = encode(".png", noise(21, 37, c.type, 1));
    const ImageHeader h = readImageHeader(png.data(), png.size(), "t");
    EXPECT_EQ(h.format, EncodedFormat::kPng);
    EXPECT_EQ(h.width, 37u);
    EXPECT_EQ(h.height, 21u);
    EXPECT_EQ(h.bit_depth, c.depth) << "type " << c.type;
    EXPECT_EQ(h.channels, c.channels) << "type " << c.type;
  }
}

TEST(ImageHeader, JpegHeaderGivesSizeDepthAndComponents) {
  for (const bool progressive : {false, true}) {
    for (const int type : {CV_8UC1, CV_8UC3}) {
      const Bytes jpg = encode(".jpg", noise(45, 70, type, 2), {cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0});
      const ImageHeader h = readImageHeader(jpg.data(), jpg.size(), "t");
      EXPECT_EQ(h.format, EncodedFormat::kJpeg);
      EXPECT_EQ(h.width, 70u);
      EXPECT_EQ(h.height, 45u);
      EXPECT_EQ(h.bit_depth, 8);
      EXPECT_EQ(h.channels, CV_MAT_CN(type));
      EXPECT_TRUE(h.dataCanHold());
    }
  }
}

TEST(ImageHeader, OtherFormatsAreRefusedByName) {
  const cv::Mat image = noise(8, 8, CV_8UC3, 3);
  EXPECT_EQ(messageOf([&] {
              const Bytes b = encode(".bmp", image);
              readImageHeader(b.data(), b.size(), "left");
            }),
            "left: BMP is not accepted, only PNG and JPEG");
  EXPECT_EQ(messageOf([&] {
              const Bytes b = encode(".tiff", image);
              readImageHeader(b.data(), b.size(), "left");
            }),
            "left: TIFF is not accepted, only PNG and JPEG");
  EXPECT_EQ(messageOf([&] {
              const Bytes b = encode(".ppm", image);
              readImageHeader(b.data(), b.size(), "left");
            }),
            "left: PNM is not accepted, only PNG and JPEG");
  const std::string gif = "GIF89a\x08\x00\x08\x00";
  EXPECT_EQ(messageOf([&] { readImageHeader(reinterpret_cast<const uint8_t*>(gif.data()), gif.size(), "left"); }),
            "left: GIF is not accepted, only PNG and JPEG");
  const Bytes junk = {0x12, 0x34, 0x56, 0x78, 0x9A};
  EXPECT_EQ(messageOf([&] { readImageHeader(junk.data(), junk.size(), "left"); }),
            "left: an unknown format (first bytes 12 34 56 78) is not accepted, only PNG and JPEG");
  EXPECT_EQ(messageOf([&] { readImageHeader(junk.data(), 0, "left"); }), "left: no image data");
}

TEST(ImageHeader, PngClaimingMoreThanItsDataCanHoldIsRefused) {
  const Bytes png = withPngSize(encode(".png", noise(16, 16, CV_8UC1, 4)), 0x7FFFFFFF, 0x7FFFFFFF);
  const ImageHeader h = readImageHeader(png.data(), png.size(), "t");
  EXPECT_EQ(h.pixels(), 0x7FFFFFFFull * 0x7FFFFFFFull);  // 64-bit: no overflow
  const std::string message = messageOf([&] { checkPngStructure(png.data(), png.size(), "f.png"); });
  EXPECT_EQ(
      message.rfind("f.png: PNG claims 2147483647x2147483647 pixels, 4611686016279904256 bytes inflated, but its ", 0), 0u)
      << message;
  // 2^31 per side is beyond what PNG allows at all.
  const Bytes beyond = withPngSize(png, 0x80000000u, 1);
  EXPECT_EQ(messageOf([&] { readImageHeader(beyond.data(), beyond.size(), "t"); }),
            "t: PNG IHDR gives the size 2147483648x1 (each side in [1, 2^31 - 1])");
}

TEST(ImageHeader, CutOrDamagedPngIsRefusedNamingTheChunk) {
  const Bytes png = encode(".png", noise(40, 50, CV_8UC3, 5));
  const Bytes half(png.begin(), png.begin() + static_cast<long>(png.size() / 2));
  EXPECT_NE(messageOf([&] { checkPngStructure(half.data(), half.size(), "t"); }).find("t: PNG is truncated in chunk IDAT"),
            std::string::npos);
  const Bytes no_end(png.begin(), png.end() - 12);
  EXPECT_EQ(messageOf([&] { checkPngStructure(no_end.data(), no_end.size(), "t"); }),
            "t: PNG has no IEND chunk: the file is cut short after " + std::to_string(no_end.size()) + " bytes");
  Bytes flipped = png;
  const size_t idat = findChunk(png, "IDAT");
  ASSERT_NE(idat, std::string::npos);
  flipped[idat + 20] ^= 0x40;
  EXPECT_EQ(messageOf([&] { checkPngStructure(flipped.data(), flipped.size(), "t"); }),
            "t: PNG chunk IDAT at byte " + std::to_string(idat) + " has a bad CRC");
  EXPECT_NO_THROW(checkPngStructure(png.data(), png.size(), "t"));
}

TEST(DecodeImageStrict, GivesOpenCvsPixelsForPngAndJpeg) {
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
    const Bytes png = encode(".png", noise(33, 47, type, 6));
    EXPECT_TRUE(identical(decodeImageStrict(png.data(), png.size(), "t", 1 << 20), cv::imdecode(png, cv::IMREAD_UNCHANGED)))
        << "PNG type " << type;
  }
  for (const bool progressive : {false, true}) {
    for (const int type : {CV_8UC1, CV_8UC3}) {
      const Bytes jpg = encode(".jpg", noise(61, 83, type, 7), {cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0});
      EXPECT_TRUE(
          identical(decodeImageStrict(jpg.data(), jpg.size(), "t", 1 << 20), cv::imdecode(jpg, cv::IMREAD_UNCHANGED)))
          << "JPEG type " << type << " progressive " << progressive;
    }
  }
}

TEST(DecodeImageStrict, JpegCutHalfwayIsRefusedWhereOpenCvPadsIt) {
  const Bytes jpg = encode(".jpg", noise(120, 160, CV_8UC3, 8));
  const Bytes half(jpg.begin(), jpg.begin() + static_cast<long>(jpg.size() / 2));
  ASSERT_FALSE(cv::imdecode(half, cv::IMREAD_UNCHANGED).empty());  // what OpenCV does: a padded image
  EXPECT_EQ(messageOf([&] { decodeImageStrict(half.data(), half.size(), "left", 1 << 20); }),
            "left: JPEG cannot be decoded: Premature end of JPEG file");
  // An end-of-image marker in the middle of the entropy-coded data.
  Bytes early_end = jpg;
  early_end[jpg.size() / 2] = 0xFF;
  early_end[jpg.size() / 2 + 1] = 0xD9;
  EXPECT_EQ(messageOf([&] {
              decodeImageStrict(early_end.data(), early_end.size(), "left", 1 << 20);
            }).rfind("left: JPEG cannot be decoded: Corrupt JPEG data", 0),
            0u);
}

TEST(DecodeImageStrict, PngWithDamagedCompressedDataIsRefused) {
  const Bytes png = encode(".png", noise(40, 50, CV_8UC1, 9));
  const size_t idat = findChunk(png, "IDAT");
  Bytes bad_zlib = png;
  bad_zlib[idat + 8] = 0x00;  // the zlib header's CMF: no longer deflate
  fixChunkCrc(bad_zlib, idat);
  EXPECT_EQ(messageOf([&] { decodeImageStrict(bad_zlib.data(), bad_zlib.size(), "t", 1 << 20); }),
            "t: PNG cannot be decoded: its compressed image data is damaged");
  // The zlib stream cut short inside a well-formed chunk (its length and CRC made to agree).
  Bytes short_stream(png.begin(), png.begin() + static_cast<long>(idat) + 8 + 100);
  put32(short_stream.data() + idat, 100);
  short_stream.resize(short_stream.size() + 4);
  fixChunkCrc(short_stream, idat);
  const Bytes iend(png.end() - 12, png.end());
  short_stream.insert(short_stream.end(), iend.begin(), iend.end());
  EXPECT_EQ(messageOf([&] { decodeImageStrict(short_stream.data(), short_stream.size(), "t", 1 << 20); }),
            "t: PNG cannot be decoded: its compressed image data is damaged");
}

TEST(DecodeImageStrict, MorePixelsThanTheLimitIsResourceExhausted) {
  const Bytes jpg = encode(".jpg", noise(30, 40, CV_8UC1, 10));
  try {
    decodeImageStrict(jpg.data(), jpg.size(), "left", 1199);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kResourceExhausted);
    EXPECT_STREQ(e.what(), "left: JPEG of 40x30 = 1200 pixels, more than the limit of 1199");
  }
  EXPECT_EQ(decodeImageStrict(jpg.data(), jpg.size(), "left", 1200).cols, 40);
}

TEST(ReadImage, PngFileClaimingAHugeSizeIsAnIoErrorBeforeDecoding) {
  const std::string path = (std::filesystem::path(::testing::TempDir()) / "huge.png").string();
  const Bytes png = withPngSize(encode(".png", noise(4, 4, CV_8UC1, 11)), 0x7FFFFFFF, 0x7FFFFFFF);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), static_cast<long>(png.size()));
  try {
    readImage(path, cv::IMREAD_UNCHANGED);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIoFailure);
    EXPECT_EQ(std::string(e.what()).rfind("cannot read image " + path + ": PNG claims 2147483647x2147483647 pixels", 0), 0u)
        << e.what();
  }
}

}  // namespace
}  // namespace cenote::io
