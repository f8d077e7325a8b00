// Wire frames into raw pairs: PNG and JPEG written by OpenCV (an independent writer) decode to
// OpenCV's pixels; everything a header gives away is refused before decoding, with the status
// code and message a client sees in its FrameAck.
#include "server/wire/frame_decoder.h"

#include <gtest/gtest.h>

#include <functional>
#include <opencv2/imgcodecs.hpp>

#include "server/wire/status_error.h"

namespace cenote::server {
namespace {

std::string encode(const std::string& ext, const cv::Mat& image) {
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes)) << ext;
  return std::string(bytes.begin(), bytes.end());
}

cv::Mat noise(int rows, int cols, int type) {
  cv::Mat m(rows, cols, type);
  cv::theRNG().state = 42;
  cv::randu(m, 0, CV_MAT_DEPTH(type) == CV_16U ? 65535 : 255);
  return m;
}

v1::StereoFrame frameOf(const std::string& left, const std::string& right) {
  v1::StereoFrame frame;
  frame.set_timestamp_s(1.0);
  frame.mutable_left()->set_encoded(left);
  frame.mutable_right()->set_encoded(right);
  return frame;
}

// The status a frame is refused with, or OK.
std::pair<grpc::StatusCode, std::string> refusal(const v1::StereoFrame& frame, const FrameLimits& limits) {
  try {
    decodeStereoFrame(frame, limits);
  } catch (const StatusError& e) {
    return {e.code(), e.what()};
  }
  return {grpc::StatusCode::OK, ""};
}

const FrameLimits kLimits{16777216, cv::Size(64, 48)};

TEST(FrameDecoder, PngAndJpegGiveOpenCvsPixels) {
  const cv::Mat grey = noise(48, 64, CV_8UC1), colour = noise(48, 64, CV_8UC3);
  for (const std::string ext : {".png", ".jpg"}) {
    const std::string left = encode(ext, grey), right = encode(ext, colour);
    const pipeline::StereoFrame raw = decodeStereoFrame(frameOf(left, right), kLimits);
    const std::vector<uint8_t> l(left.begin(), left.end()), r(right.begin(), right.end());
    EXPECT_EQ(cv::norm(raw.left, cv::imdecode(l, cv::IMREAD_UNCHANGED), cv::NORM_INF), 0.0) << ext;
    EXPECT_EQ(cv::norm(raw.right, cv::imdecode(r, cv::IMREAD_UNCHANGED), cv::NORM_INF), 0.0) << ext;
    EXPECT_EQ(raw.left.type(), CV_8UC1);
    EXPECT_EQ(raw.right.type(), CV_8UC3);
  }
}

TEST(FrameDecoder, OnlyPngAndJpegAreAccepted) {
  const std::string png = encode(".png", noise(48, 64, CV_8UC1));
  EXPECT_EQ(
      refusal(frameOf(encode(".bmp", noise(48, 64, CV_8UC3)), png), kLimits),
      std::make_pair(grpc::StatusCode::INVALID_ARGUMENT, std::string("left: BMP is not accepted, only PNG and JPEG")));
  EXPECT_EQ(
      refusal(frameOf(png, encode(".tiff", noise(48, 64, CV_8UC1))), kLimits),
      std::make_pair(grpc::StatusCode::INVALID_ARGUMENT, std::string("right: TIFF is not accepted, only PNG and JPEG")));
}

TEST(FrameDecoder, SizeBeyondTheLimitIsRefusedFromTheHeader) {
  // A real 8000x6000 PNG of one grey level: 48 M pixels in a few KB of file.
  const std::string big = encode(".png", cv::Mat(6000, 8000, CV_8UC1, cv::Scalar(7)));
  ASSERT_LT(big.size(), 200000u);
  EXPECT_EQ(refusal(frameOf(big, big), {16777216, cv::Size()}),
            std::make_pair(grpc::StatusCode::RESOURCE_EXHAUSTED,
                           std::string("left: 8000x6000 = 48000000 pixels, more than the limit "
                                       "server.limits.max_image_pixels = 16777216")));
}

TEST(FrameDecoder, SizeThatDisagreesWithTheCalibrationIsRefusedFromTheHeader) {
  const std::string good = encode(".png", noise(48, 64, CV_8UC1));
  const std::string jpg = encode(".jpg", noise(60, 80, CV_8UC3));
  EXPECT_EQ(refusal(frameOf(good, jpg), kLimits),
            std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                           std::string("right image is 80x60 but the calibration is for 64x48")));
}

TEST(FrameDecoder, SixteenBitPngIsRefused) {
  const std::string good = encode(".png", noise(48, 64, CV_8UC1));
  EXPECT_EQ(refusal(frameOf(encode(".png", noise(48, 64, CV_16UC1)), good), kLimits),
            std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                           std::string("left: PNG has 16-bit samples; frames must be 8-bit")));
}

TEST(FrameDecoder, TruncatedImagesAreRefused) {
  const std::string png = encode(".png", noise(48, 64, CV_8UC1)), jpg = encode(".jpg", noise(48, 64, CV_8UC3));
  EXPECT_EQ(refusal(frameOf(png, jpg.substr(0, jpg.size() / 2)), kLimits),
            std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                           std::string("right: JPEG cannot be decoded: Premature end of JPEG file")));
  const std::string no_end = png.substr(0, png.size() - 12);
  EXPECT_EQ(refusal(frameOf(no_end, jpg), kLimits),
            std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                           std::string("left: PNG has no IEND chunk: the file is cut short after " +
                                       std::to_string(no_end.size()) + " bytes")));
}

TEST(FrameDecoder, RawPixelCountIsComputedIn64Bits) {
  v1::StereoFrame frame = frameOf("", encode(".png", noise(48, 64, CV_8UC1)));
  v1::RawImage* raw = frame.mutable_left()->mutable_raw();
  raw->set_width(0xFFFFFFFFu);
  raw->set_height(0xFFFFFFFFu);
  raw->set_encoding(v1::IMAGE_ENCODING_BGR8);
  raw->set_data(std::string(16, '\0'));
  EXPECT_EQ(refusal(frame, kLimits),
            std::make_pair(grpc::StatusCode::RESOURCE_EXHAUSTED,
                           std::string("left: 4294967295x4294967295 = 18446744065119617025 pixels, more than the limit "
                                       "server.limits.max_image_pixels = 16777216")));
  raw->set_width(64);
  raw->set_height(48);
  EXPECT_EQ(refusal(frame, kLimits),
            std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                           std::string("left: raw image has 16 bytes, expected 9216 for 64x48x3")));
  raw->set_width(65);
  EXPECT_EQ(refusal(frame, kLimits), std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                                                    std::string("left image is 65x48 but the calibration is for 64x48")));
}

// A raw colour camera's mosaic of a 64x48 scene whose left half is one colour and right half another,
// laid out here pixel by pixel from the pattern's name (its first two rows), not by OpenCV.
std::string bayerMosaic(const char* pattern, cv::Vec3b left, cv::Vec3b right) {
  std::string bytes(64 * 48, '\0');
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      const char colour = pattern[(y % 2) * 2 + x % 2];
      const int channel = colour == 'b' ? 0 : colour == 'g' ? 1 : 2;
      bytes[y * 64 + x] = static_cast<char>((x < 32 ? left : right)[channel]);
    }
  }
  return bytes;
}

TEST(FrameDecoder, RawBayerMosaicsOfEveryPatternAreDemosaicedToTheirColours) {
  const cv::Vec3b left(20, 60, 200), right(210, 120, 30);  // B, G, R
  const std::pair<const char*, v1::ImageEncoding> patterns[] = {{"rggb", v1::IMAGE_ENCODING_BAYER_RGGB8},
                                                                {"bggr", v1::IMAGE_ENCODING_BAYER_BGGR8},
                                                                {"gbrg", v1::IMAGE_ENCODING_BAYER_GBRG8},
                                                                {"grbg", v1::IMAGE_ENCODING_BAYER_GRBG8}};
  for (const auto& [pattern, encoding] : patterns) {
    v1::StereoFrame frame;
    frame.set_timestamp_s(1.0);
    for (v1::Image* image : {frame.mutable_left(), frame.mutable_right()}) {
      v1::RawImage* raw = image->mutable_raw();
      raw->set_width(64);
      raw->set_height(48);
      raw->set_encoding(encoding);
      raw->set_data(bayerMosaic(pattern, left, right));
    }
    const pipeline::StereoFrame decoded = decodeStereoFrame(frame, kLimits);
    ASSERT_EQ(decoded.left.type(), CV_8UC3) << pattern;
    // A flat colour demosaics to itself away from the colour edge and the border.
    for (int y = 2; y < 46; ++y) {
      for (int x : {2, 15, 29, 34, 50, 61}) {
        ASSERT_EQ(decoded.left.at<cv::Vec3b>(y, x), x < 32 ? left : right) << pattern << " at " << x << ", " << y;
      }
    }
    EXPECT_EQ(cv::norm(decoded.left, decoded.right, cv::NORM_INF), 0.0) << pattern;
  }
}

TEST(FrameDecoder, UnknownRawEncodingIsRefusedByNumber) {
  v1::StereoFrame frame = frameOf("", encode(".png", noise(48, 64, CV_8UC1)));
  v1::RawImage* raw = frame.mutable_left()->mutable_raw();
  raw->set_width(64);
  raw->set_height(48);
  raw->set_data(std::string(64 * 48, '\0'));
  for (int encoding : {0, 8}) {
    raw->set_encoding(static_cast<v1::ImageEncoding>(encoding));
    EXPECT_EQ(refusal(frame, kLimits),
              std::make_pair(grpc::StatusCode::INVALID_ARGUMENT,
                             "left: raw image encoding " + std::to_string(encoding) +
                                 " is not one of MONO8, BGR8, RGB8, BAYER_RGGB8, BAYER_BGGR8, BAYER_GBRG8 or BAYER_GRBG8"));
  }
}

}  // namespace
}  // namespace cenote::server
