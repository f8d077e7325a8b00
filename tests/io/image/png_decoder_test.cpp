#include "io/image/png_decoder.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "io/image/image_io.h"
#include "io/image/png_unfilter.h"
#include "tests/support/test_data.h"

namespace cenote::io {
namespace {

// A PNG written by hand, so that every filter type appears (OpenCV's encoder only uses Sub).
// The zlib stream uses stored (uncompressed) blocks: valid deflate that needs no library.
class HandPng {
 public:
  static std::vector<uint8_t> encode(const cv::Mat& bgr_or_grey, int bit_depth = 8) {
    const int channels = bgr_or_grey.channels();
    const int colour_type = channels == 1 ? 0 : channels == 3 ? 2 : 6;
    std::vector<uint8_t> raw;
    const int bpp = channels;
    std::vector<uint8_t> prev(static_cast<size_t>(bgr_or_grey.cols) * channels, 0);
    for (int y = 0; y < bgr_or_grey.rows; ++y) {
      std::vector<uint8_t> row(prev.size());
      for (int x = 0; x < bgr_or_grey.cols; ++x) {
        for (int c = 0; c < channels; ++c) {
          // PNG stores RGB(A); OpenCV holds BGR(A).
          const int from = channels >= 3 && c < 3 ? 2 - c : c;
          row[x * channels + c] = bgr_or_grey.ptr<uint8_t>(y)[x * channels + from];
        }
      }
      const int filter = y % 5;
      raw.push_back(static_cast<uint8_t>(filter));
      for (size_t i = 0; i < row.size(); ++i) {
        const int a = i >= static_cast<size_t>(bpp) ? row[i - bpp] : 0, b = prev[i];
        const int c = i >= static_cast<size_t>(bpp) ? prev[i - bpp] : 0;
        int predictor = 0;
        if (filter == 1) predictor = a;
        if (filter == 2) predictor = b;
        if (filter == 3) predictor = (a + b) / 2;
        if (filter == 4) {
          const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
          predictor = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
        }
        raw.push_back(static_cast<uint8_t>(row[i] - predictor));
      }
      prev = row;
    }
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<uint8_t> header;
    put32(header, bgr_or_grey.cols);
    put32(header, bgr_or_grey.rows);
    header.insert(header.end(), {static_cast<uint8_t>(bit_depth), static_cast<uint8_t>(colour_type), 0, 0, 0});
    chunk(png, "IHDR", header);
    chunk(png, "tEXt", {'a', 0, 'b'});
    const std::vector<uint8_t> z = zlibStored(raw);
    // Two IDAT chunks: the decoder must join them.
    const size_t half = z.size() / 2;
    chunk(png, "IDAT", std::vector<uint8_t>(z.begin(), z.begin() + half));
    chunk(png, "IDAT", std::vector<uint8_t>(z.begin() + half, z.end()));
    chunk(png, "IEND", {});
    return png;
  }

  static void chunk(std::vector<uint8_t>& png, const char* type, const std::vector<uint8_t>& body) {
    put32(png, static_cast<uint32_t>(body.size()));
    std::vector<uint8_t> typed(type, type + 4);
    typed.insert(typed.end(), body.begin(), body.end());
    png.insert(png.end(), typed.begin(), typed.end());
    put32(png, crc32(typed));
  }

 private:
  static void put32(std::vector<uint8_t>& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<uint8_t>(v >> s));
  }
  static uint32_t crc32(const std::vector<uint8_t>& bytes) {
    uint32_t crc = 0xFFFFFFFFu;
    for (uint8_t b : bytes) {
      crc ^= b;
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
  }
  static std::vector<uint8_t> zlibStored(const std::vector<uint8_t>& data) {
    std::vector<uint8_t> z = {0x78, 0x01};
    size_t pos = 0;
    do {
      const size_t n = std::min<size_t>(65535, data.size() - pos);
      z.push_back(pos + n == data.size() ? 1 : 0);  // BFINAL, BTYPE = stored
      z.insert(z.end(), {static_cast<uint8_t>(n), static_cast<uint8_t>(n >> 8), static_cast<uint8_t>(~n),
                         static_cast<uint8_t>(~n >> 8)});
      z.insert(z.end(), data.begin() + pos, data.begin() + pos + n);
      pos += n;
    } while (pos < data.size());
    uint32_t a = 1, b = 0;
    for (uint8_t v : data) {
      a = (a + v) % 65521;
      b = (b + a) % 65521;
    }
    put32(z, (b << 16) | a);
    return z;
  }
};

cv::Mat randomImage(int rows, int cols, int channels, uint64_t seed) {
  cv::Mat image(rows, cols, CV_MAKETYPE(CV_8U, channels));
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

void expectSamePixels(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  ASSERT_FALSE(a.empty()) << what;
  ASSERT_EQ(a.type(), b.type()) << what;
  ASSERT_EQ(a.size(), b.size()) << what;
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << what;
}

TEST(PngDecoder, EveryFilterTypeGivesOpenCvsPixelsForGreyRgbAndRgba) {
  for (int channels : {1, 3, 4}) {
    const cv::Mat image = randomImage(23, 37, channels, 7 + channels);
    const std::vector<uint8_t> png = HandPng::encode(image);
    const cv::Mat fast = decodePngFast(png.data(), png.size());
    const std::string what = std::to_string(channels) + " channels";
    expectSamePixels(fast, cv::imdecode(png, cv::IMREAD_UNCHANGED), what + " vs OpenCV");
    expectSamePixels(fast, image, what + " vs the encoded image");
  }
}

// The SIMD Sub filter of RGB rows on every instruction set, against the filter's definition, for
// rows shorter than a block, with and without a tail, and an 800-pixel row; in place and not.
TEST(PngDecoder, SubFilterOfRgbRowsIsTheDefinitionOnEveryInstructionSet) {
  cv::RNG rng(5);
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    for (const std::size_t length : {0, 2, 3, 15, 16, 17, 47, 48, 111, 2400}) {
      std::vector<uint8_t> in(length);
      for (uint8_t& b : in) b = static_cast<uint8_t>(rng.uniform(0, 256));
      std::vector<uint8_t> want(length);
      for (std::size_t i = 0; i < length; ++i) want[i] = static_cast<uint8_t>(in[i] + (i >= 3 ? want[i - 3] : 0));
      std::vector<uint8_t> out(length, 0xAB), in_place = in;
      detail::unfilterSubRgb(in.data(), out.data(), length);
      detail::unfilterSubRgb(in_place.data(), in_place.data(), length);
      EXPECT_EQ(out, want) << hwy::TargetName(target) << ", " << length << " bytes";
      EXPECT_EQ(in_place, want) << hwy::TargetName(target) << ", " << length << " bytes in place";
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(PngDecoder, OpenCvEncodedImagesDecodeToTheSamePixels) {
  for (int channels : {1, 3, 4}) {
    const cv::Mat image = randomImage(61, 80, channels, 100 + channels);
    std::vector<uint8_t> png;
    ASSERT_TRUE(cv::imencode(".png", image, png));
    expectSamePixels(decodePngFast(png.data(), png.size()), image, std::to_string(channels) + " channels");
  }
}

TEST(PngDecoder, LeavesWhatItDoesNotHandleToOpenCv) {
  // 16-bit: handled by OpenCV (depth PNGs).
  cv::Mat deep(5, 6, CV_16UC1, cv::Scalar(1234));
  std::vector<uint8_t> png16;
  ASSERT_TRUE(cv::imencode(".png", deep, png16));
  EXPECT_TRUE(decodePngFast(png16.data(), png16.size()).empty());
  // A damaged chunk (CRC mismatch), a truncated file, a transparency chunk, not a PNG at all.
  const cv::Mat image = randomImage(9, 10, 3, 3);
  std::vector<uint8_t> png = HandPng::encode(image);
  std::vector<uint8_t> damaged = png;
  damaged[40] ^= 0xFF;
  EXPECT_TRUE(decodePngFast(damaged.data(), damaged.size()).empty());
  EXPECT_TRUE(decodePngFast(png.data(), png.size() - 20).empty());
  std::vector<uint8_t> with_trns(png.begin(), png.begin() + 33);  // signature + IHDR
  HandPng::chunk(with_trns, "tRNS", {0, 1, 0, 2, 0, 3});
  with_trns.insert(with_trns.end(), png.begin() + 33, png.end());
  EXPECT_TRUE(decodePngFast(with_trns.data(), with_trns.size()).empty());
  const std::vector<uint8_t> text = {'h', 'e', 'l', 'l', 'o'};
  EXPECT_TRUE(decodePngFast(text.data(), text.size()).empty());
}

TEST(PngDecoder, ReadImageGivesOpenCvsResultForFastAndFallbackFiles) {
  const std::string dir = testing::TempDir();
  const cv::Mat colour = randomImage(31, 17, 3, 11);
  const std::vector<uint8_t> png = HandPng::encode(colour);
  const std::string path = dir + "/hand.png";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), png.size());
  for (int flags : {cv::IMREAD_UNCHANGED, cv::IMREAD_COLOR, cv::IMREAD_GRAYSCALE}) {
    expectSamePixels(readImage(path, flags), cv::imread(path, flags), "flags " + std::to_string(flags));
  }
  const std::string deep_path = dir + "/deep.png";
  ASSERT_TRUE(cv::imwrite(deep_path, cv::Mat(4, 4, CV_16UC1, cv::Scalar(700))));
  expectSamePixels(readImage(deep_path, cv::IMREAD_UNCHANGED), cv::imread(deep_path, cv::IMREAD_UNCHANGED), "16-bit");
}

TEST(PngDecoder, RealPngFilesMatchOpenCv) {
  // Middlebury pairs beside the project (skip when absent).
  const std::filesystem::path data = std::filesystem::path(test::sharedDataDir()) / "middlebury";
  int compared = 0;
  for (const char* name : {"cones/im2.png", "cones/disp2.png", "Cloth3/view1.png", "Cloth3/disp1.png"}) {
    const std::string path = (data / name).string();
    if (!std::filesystem::exists(path)) continue;
    expectSamePixels(readImage(path, cv::IMREAD_UNCHANGED), cv::imread(path, cv::IMREAD_UNCHANGED), path);
    ++compared;
  }
  if (compared == 0) GTEST_SKIP() << "no Middlebury data in " << data;
}

}  // namespace
}  // namespace cenote::io
