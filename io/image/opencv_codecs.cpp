#include "io/image/opencv_codecs.h"

#include <limits>

#include "common/error.h"
#include "common/plugin_library.h"

namespace cenote::io {
namespace {

using DecodeFn = bool (*)(const uint8_t*, std::size_t, int, cv::Mat*, cv::Exception*);
using EncodeFn = bool (*)(const char*, const cv::Mat*, const int*, std::size_t, std::vector<uint8_t>*, bool*,
                          cv::Exception*);

PluginLibrary& plugin() {
  static PluginLibrary library(CENOTE_CVCODECS_PATH, "libcenote_cvcodecs.so");
  return library;
}

}  // namespace

cv::Mat opencvDecode(const uint8_t* data, std::size_t size, int flags) {
  if (size == 0) return {};
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw ResourceExhaustedError("image of " + std::to_string(size) + " bytes, more than OpenCV takes (2^31 - 1)");
  }
  static const DecodeFn decode = plugin().function<DecodeFn>("cenote_cv_decode");
  cv::Mat out;
  cv::Exception error;
  if (!decode(data, size, flags, &out, &error)) throw error;
  return out;
}

bool opencvEncode(const std::string& ext, const cv::Mat& image, std::vector<uint8_t>& bytes,
                  const std::vector<int>& params) {
  static const EncodeFn encode = plugin().function<EncodeFn>("cenote_cv_encode");
  bool ok = false;
  cv::Exception error;
  if (!encode(ext.c_str(), &image, params.data(), params.size(), &bytes, &ok, &error)) throw error;
  return ok;
}

}  // namespace cenote::io
