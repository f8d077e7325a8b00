#include "server/wire/frame_decoder.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "server/wire/status_error.h"

namespace cenote::server {
namespace {

cv::Mat decodeRaw(const v1::RawImage& raw, const std::string& what, int64_t max_pixels) {
  int channels = 0;
  switch (raw.encoding()) {
    case v1::IMAGE_ENCODING_MONO8: channels = 1; break;
    case v1::IMAGE_ENCODING_BGR8:
    case v1::IMAGE_ENCODING_RGB8: channels = 3; break;
    default: throw invalidArgument(what + ": raw image encoding is unspecified (MONO8, BGR8 or RGB8)");
  }
  const int64_t pixels = int64_t{raw.width()} * raw.height();
  if (pixels == 0)
    throw invalidArgument(what + ": raw image is empty (" + std::to_string(raw.width()) + "x" +
                          std::to_string(raw.height()) + ")");
  if (pixels > max_pixels) {
    throw resourceExhausted(what + ": " + std::to_string(pixels) +
                            " pixels, more than the limit server.limits.max_image_pixels = " + std::to_string(max_pixels));
  }
  const int64_t expected = pixels * channels;
  if (static_cast<int64_t>(raw.data().size()) != expected) {
    throw invalidArgument(what + ": raw image has " + std::to_string(raw.data().size()) + " bytes, expected " +
                          std::to_string(expected) + " for " + std::to_string(raw.width()) + "x" +
                          std::to_string(raw.height()) + "x" + std::to_string(channels));
  }
  const cv::Mat view(static_cast<int>(raw.height()), static_cast<int>(raw.width()), CV_8UC(channels),
                     const_cast<char*>(raw.data().data()));
  cv::Mat image;
  if (raw.encoding() == v1::IMAGE_ENCODING_RGB8) {
    cv::cvtColor(view, image, cv::COLOR_RGB2BGR);
  } else {
    image = view.clone();
  }
  return image;
}

cv::Mat decodeImage(const v1::Image& image, const std::string& what, int64_t max_pixels) {
  if (image.has_raw()) return decodeRaw(image.raw(), what, max_pixels);
  if (image.encoded().empty()) throw invalidArgument(what + ": no image data");
  const cv::Mat bytes(1, static_cast<int>(image.encoded().size()), CV_8U, const_cast<char*>(image.encoded().data()));
  cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  if (decoded.empty()) {
    throw invalidArgument(what + ": " + std::to_string(image.encoded().size()) +
                          " bytes that OpenCV cannot decode as an image (corrupt, or not PNG / JPEG)");
  }
  if (decoded.depth() != CV_8U) throw invalidArgument(what + ": image is not 8-bit");
  if (int64_t{decoded.cols} * decoded.rows > max_pixels) {
    throw resourceExhausted(what +
                            ": more pixels than the limit server.limits.max_image_pixels = " + std::to_string(max_pixels));
  }
  return decoded;
}

}  // namespace

pipeline::StereoFrame decodeStereoFrame(const v1::StereoFrame& frame, int64_t max_pixels) {
  pipeline::StereoFrame out;
  out.t_s = frame.timestamp_s();
  out.left = decodeImage(frame.left(), "left", max_pixels);
  out.right = decodeImage(frame.right(), "right", max_pixels);
  if (out.left.size() != out.right.size()) {
    throw invalidArgument("left image is " + std::to_string(out.left.cols) + "x" + std::to_string(out.left.rows) +
                          " but right is " + std::to_string(out.right.cols) + "x" + std::to_string(out.right.rows));
  }
  return out;
}

}  // namespace cenote::server
