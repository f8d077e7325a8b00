// opencv_codec_plugin.cpp: libcenote_cvcodecs.so, OpenCV's image codecs behind a C interface for
// dlopen (opencv_codecs.h). cv::Mat crosses the boundary by pointer: the plugin and the program
// share the one libopencv_core of the process. Exceptions never cross it: a cv::Exception comes
// back as a copy (*error), which the caller throws again.
#include <cstddef>
#include <cstdint>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

extern "C" {

// cv::imdecode into *out; false with *error set when OpenCV throws.
__attribute__((visibility("default"))) bool cenote_cv_decode(const uint8_t* data, std::size_t size, int flags, cv::Mat* out,
                                                             cv::Exception* error) {
  try {
    *out = cv::imdecode(cv::Mat(1, static_cast<int>(size), CV_8U, const_cast<uint8_t*>(data)), flags);
    return true;
  } catch (const cv::Exception& e) {
    *error = e;
    return false;
  }
}

// cv::imencode into *bytes; *ok is imencode's result; false with *error set when OpenCV throws.
__attribute__((visibility("default"))) bool cenote_cv_encode(const char* ext, const cv::Mat* image, const int* params,
                                                             std::size_t num_params, std::vector<uint8_t>* bytes, bool* ok,
                                                             cv::Exception* error) {
  try {
    *ok = cv::imencode(ext, *image, *bytes, std::vector<int>(params, params + num_params));
    return true;
  } catch (const cv::Exception& e) {
    *error = e;
    return false;
  }
}
}
