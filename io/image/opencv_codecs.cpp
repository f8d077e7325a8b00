#include "io/image/opencv_codecs.h"

#include <dlfcn.h>

#include <limits>
#include <mutex>

#include "common/error.h"

namespace cenote::io {
namespace {

using DecodeFn = bool (*)(const uint8_t*, std::size_t, int, cv::Mat*, cv::Exception*);
using EncodeFn = bool (*)(const char*, const cv::Mat*, const int*, std::size_t, std::vector<uint8_t>*, bool*,
                          cv::Exception*);

struct Plugin {
  DecodeFn decode = nullptr;
  EncodeFn encode = nullptr;
};

// Where the build put the plugin (CMake's CENOTE_CVCODECS_PATH), else the loader's search path.
void* openPlugin(std::string& tried) {
  for (const char* path : {CENOTE_CVCODECS_PATH, "libcenote_cvcodecs.so"}) {
    if (void* handle = dlopen(path, RTLD_NOW | RTLD_LOCAL)) return handle;
    tried += std::string("\n  ") + path + ": " + dlerror();
  }
  return nullptr;
}

const Plugin& plugin() {
  static std::once_flag once;
  static Plugin loaded;
  static std::string failure;
  std::call_once(once, [] {
    std::string tried;
    void* handle = openPlugin(tried);
    if (!handle) {
      failure = "cannot open OpenCV's image codecs (libcenote_cvcodecs.so):" + tried;
      return;
    }
    loaded.decode = reinterpret_cast<DecodeFn>(dlsym(handle, "cenote_cv_decode"));
    loaded.encode = reinterpret_cast<EncodeFn>(dlsym(handle, "cenote_cv_encode"));
    if (!loaded.decode || !loaded.encode) failure = "libcenote_cvcodecs.so lacks cenote_cv_decode or cenote_cv_encode";
  });
  if (!failure.empty()) throw FailedPreconditionError(failure);
  return loaded;
}

}  // namespace

cv::Mat opencvDecode(const uint8_t* data, std::size_t size, int flags) {
  if (size == 0) return {};
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw ResourceExhaustedError("image of " + std::to_string(size) + " bytes, more than OpenCV takes (2^31 - 1)");
  }
  cv::Mat out;
  cv::Exception error;
  if (!plugin().decode(data, size, flags, &out, &error)) throw error;
  return out;
}

bool opencvEncode(const std::string& ext, const cv::Mat& image, std::vector<uint8_t>& bytes,
                  const std::vector<int>& params) {
  bool ok = false;
  cv::Exception error;
  if (!plugin().encode(ext.c_str(), &image, params.data(), params.size(), &bytes, &ok, &error)) throw error;
  return ok;
}

}  // namespace cenote::io
