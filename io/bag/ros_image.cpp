#include "io/bag/ros_image.h"

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "io/image/opencv_codecs.h"
#include "io/image/png_decoder.h"

namespace cenote::io {
namespace {

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

cv::Mat imageToMat(const RosImage& image, const std::string& topic) {
  const std::string& enc = image.encoding;
  const std::string where = "topic " + topic + ": image encoding " + enc;
  if (startsWith(enc, "bayer_")) {
    throw Error(where + " is a raw Bayer mosaic; cenote reads mono8, bgr8, rgb8, bgra8 and rgba8 (debayer it "
                        "first: record image_mono or image_color, or run image_proc)");
  }
  int channels = 0;
  if (enc == "mono8" || enc == "8UC1") {
    channels = 1;
  } else if (enc == "bgr8" || enc == "rgb8" || enc == "8UC3") {
    channels = 3;
  } else if (enc == "bgra8" || enc == "rgba8" || enc == "8UC4") {
    channels = 4;
  } else {
    throw Error(where + " is not read; cenote reads mono8, bgr8, rgb8, bgra8 and rgba8 (8-bit grey or colour)");
  }
  const std::size_t row_bytes = static_cast<std::size_t>(image.width) * channels;
  if (image.width == 0 || image.height == 0) throw Error("topic " + topic + ": empty image (" + enc + ")");
  if (image.step < row_bytes) {
    throw Error("topic " + topic + ": image step " + std::to_string(image.step) + " is less than width " +
                std::to_string(image.width) + " x " + std::to_string(channels) + " bytes");
  }
  if (image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    throw Error("topic " + topic + ": image data holds " + std::to_string(image.data.size()) + " bytes, " +
                std::to_string(image.height) + " rows of step " + std::to_string(image.step) + " need " +
                std::to_string(static_cast<std::size_t>(image.step) * image.height));
  }
  const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC(channels),
                     const_cast<std::uint8_t*>(image.data.data()), image.step);
  cv::Mat out;
  if (enc == "rgb8") {
    cv::cvtColor(view, out, cv::COLOR_RGB2BGR);
  } else if (enc == "rgba8") {
    cv::cvtColor(view, out, cv::COLOR_RGBA2BGR);
  } else if (channels == 4) {
    cv::cvtColor(view, out, cv::COLOR_BGRA2BGR);
  } else {
    out = view.clone();
  }
  return out;
}

cv::Mat compressedImageToMat(const RosCompressedImage& image, const std::string& topic) {
  const auto& d = image.data;
  const bool png = d.size() >= 8 && std::memcmp(d.data(), "\x89PNG\r\n\x1a\n", 8) == 0;
  const bool jpeg = d.size() >= 3 && d[0] == 0xFF && d[1] == 0xD8 && d[2] == 0xFF;
  const std::string where = "topic " + topic + ": compressed image (format '" + image.format + "', " +
                            std::to_string(d.size()) + " bytes)";
  if (!png && !jpeg) throw Error(where + " is neither JPEG nor PNG");
  cv::Mat out;
  if (png) out = decodePngFast(d.data(), d.size());
  if (out.empty()) {
    out = opencvDecode(d.data(), d.size(), cv::IMREAD_UNCHANGED);
  }
  if (out.empty()) throw Error(where + " cannot be decoded");
  if (out.depth() != CV_8U) throw Error(where + " is not 8-bit; cenote reads 8-bit grey or colour images");
  if (out.channels() == 4) cv::cvtColor(out, out, cv::COLOR_BGRA2BGR);
  return out;
}

}  // namespace cenote::io
