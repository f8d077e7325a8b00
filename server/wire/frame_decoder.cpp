#include "server/wire/frame_decoder.h"

#include <opencv2/imgproc.hpp>

#include "io/image/image_header.h"
#include "io/image/image_io.h"
#include "server/wire/status_error.h"

namespace cenote::server {
namespace {

std::string sizeText(uint64_t width, uint64_t height) { return std::to_string(width) + "x" + std::to_string(height); }

void checkPixels(uint64_t width, uint64_t height, const std::string& what, const FrameLimits& limits) {
  const uint64_t pixels = width * height;  // both below 2^32: no overflow
  if (pixels == 0) throw invalidArgument(what + ": image is empty (" + sizeText(width, height) + ")");
  if (pixels > static_cast<uint64_t>(limits.max_pixels)) {
    throw resourceExhausted(
        what + ": " + sizeText(width, height) + " = " + std::to_string(pixels) +
        " pixels, more than the limit server.limits.max_image_pixels = " + std::to_string(limits.max_pixels));
  }
  if (!limits.image_size.empty() && (width != static_cast<uint64_t>(limits.image_size.width) ||
                                     height != static_cast<uint64_t>(limits.image_size.height))) {
    throw invalidArgument(what + " image is " + sizeText(width, height) + " but the calibration is for " +
                          sizeText(limits.image_size.width, limits.image_size.height));
  }
}

// The cv::cvtColor code that makes a raw encoding's pixels grey or BGR (-1: they are), and its bytes a pixel.
struct RawLayout {
  int channels = 0;
  int to_bgr = -1;
};

RawLayout rawLayout(v1::ImageEncoding encoding, const std::string& what) {
  switch (encoding) {
    case v1::IMAGE_ENCODING_MONO8: return {1};
    case v1::IMAGE_ENCODING_BGR8: return {3};
    case v1::IMAGE_ENCODING_RGB8: return {3, cv::COLOR_RGB2BGR};
    // OpenCV 4 names its Bayer codes by the first two rows too.
    case v1::IMAGE_ENCODING_BAYER_RGGB8: return {1, cv::COLOR_BayerRGGB2BGR};
    case v1::IMAGE_ENCODING_BAYER_BGGR8: return {1, cv::COLOR_BayerBGGR2BGR};
    case v1::IMAGE_ENCODING_BAYER_GBRG8: return {1, cv::COLOR_BayerGBRG2BGR};
    case v1::IMAGE_ENCODING_BAYER_GRBG8: return {1, cv::COLOR_BayerGRBG2BGR};
    default:
      throw invalidArgument(what + ": raw image encoding " + std::to_string(encoding) +
                            " is not one of MONO8, BGR8, RGB8, BAYER_RGGB8, BAYER_BGGR8, BAYER_GBRG8 or BAYER_GRBG8");
  }
}

cv::Mat decodeRaw(const v1::RawImage& raw, const std::string& what, const FrameLimits& limits) {
  const RawLayout layout = rawLayout(raw.encoding(), what);
  const int channels = layout.channels;
  checkPixels(raw.width(), raw.height(), what, limits);
  const uint64_t expected = uint64_t{raw.width()} * raw.height() * channels;
  if (raw.data().size() != expected) {
    throw invalidArgument(what + ": raw image has " + std::to_string(raw.data().size()) + " bytes, expected " +
                          std::to_string(expected) + " for " + sizeText(raw.width(), raw.height()) + "x" +
                          std::to_string(channels));
  }
  const cv::Mat view(static_cast<int>(raw.height()), static_cast<int>(raw.width()), CV_8UC(channels),
                     const_cast<char*>(raw.data().data()));
  if (layout.to_bgr < 0) return view.clone();  // the message's bytes go with the message
  cv::Mat image;
  cv::cvtColor(view, image, layout.to_bgr);
  return image;
}

cv::Mat decodeEncoded(const std::string& encoded, const std::string& what, const FrameLimits& limits) {
  const auto* data = reinterpret_cast<const uint8_t*>(encoded.data());
  try {
    // The header alone first: size, depth and channels are refused before any pixel is decoded.
    const io::ImageHeader header = io::readImageHeader(data, encoded.size(), what);
    checkPixels(header.width, header.height, what, limits);
    if (header.bit_depth != 8) {
      throw invalidArgument(what + ": " + io::toString(header.format) + " has " + std::to_string(header.bit_depth) +
                            "-bit samples; frames must be 8-bit");
    }
    if (header.format == io::EncodedFormat::kPng && header.channels == 2) {
      throw invalidArgument(what + ": PNG is grey with alpha (2 channels); frames are grey, BGR or BGRA");
    }
    cv::Mat image = io::decodeImageStrict(data, encoded.size(), what, static_cast<uint64_t>(limits.max_pixels));
    // What the decoder gives must be what the pipeline takes (8-bit, 1, 3 or 4 channels).
    if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3 && image.channels() != 4)) {
      throw invalidArgument(what + ": decoded to " + std::to_string(image.channels()) + " channels of depth " +
                            std::to_string(image.depth()) + "; frames are 8-bit grey, BGR or BGRA");
    }
    return image;
  } catch (const Error& e) {
    throw toStatusError(e);
  }
}

cv::Mat decodeImage(const v1::Image& image, const std::string& what, const FrameLimits& limits) {
  if (image.has_raw()) return decodeRaw(image.raw(), what, limits);
  if (image.encoded().empty()) throw invalidArgument(what + ": no image data");
  return decodeEncoded(image.encoded(), what, limits);
}

}  // namespace

pipeline::StereoFrame decodeStereoFrame(const v1::StereoFrame& frame, const FrameLimits& limits) {
  pipeline::StereoFrame out;
  out.t_s = frame.timestamp_s();
  out.left = decodeImage(frame.left(), "left", limits);
  out.right = decodeImage(frame.right(), "right", limits);
  if (out.left.size() != out.right.size()) {
    throw invalidArgument("left image is " + sizeText(out.left.cols, out.left.rows) + " but right is " +
                          sizeText(out.right.cols, out.right.rows));
  }
  return out;
}

}  // namespace cenote::server
