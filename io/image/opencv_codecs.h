// opencv_codecs.h: OpenCV's image codecs (libopencv_imgcodecs: cv::imdecode, cv::imencode),
// loaded on first use. imgcodecs pulls about a hundred shared libraries into a process (GDAL,
// GDCM, libheif, OpenEXR...), which the dynamic loader maps and relocates at every start of every
// program that links it: most of what `cenote --help` cost. cenote decodes its own 8-bit PNGs and
// strict JPEGs (png_decoder.h, jpeg_decoder.h); OpenCV's codecs are needed only for the other
// kinds, for JPEG encoding and for the report's images, so they live in a plugin of their own
// (opencv_codec_plugin.cpp, built as libcenote_cvcodecs.so beside the programs' build tree) that
// the first call opens with dlopen.
// Threads: any number of calls may run concurrently (the plugin is opened once).
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace cenote::io {

// cv::imdecode(data, flags): an empty Mat when OpenCV cannot decode the bytes (or size is 0).
// @throws cenote::FailedPreconditionError when the plugin cannot be opened (naming its paths and
//         why); cenote::ResourceExhaustedError for 2^31 bytes or more (OpenCV's limit); the
//         cv::Exception OpenCV threw, as it threw it.
cv::Mat opencvDecode(const uint8_t* data, std::size_t size, int flags);

// cv::imencode(ext, image, bytes, params).
// @return false when OpenCV refuses the image. @throws as opencvDecode (no size limit).
bool opencvEncode(const std::string& ext, const cv::Mat& image, std::vector<uint8_t>& bytes,
                  const std::vector<int>& params = {});

}  // namespace cenote::io
