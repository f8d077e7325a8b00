// png_decoder.h: fast decoding of the PNG files that stereo sequences are made of (8-bit grey,
// RGB or RGBA, not interlaced), with libdeflate instead of zlib: inflating is most of a PNG's
// decoding time, and libdeflate inflates about three times faster. Anything else (16-bit, palette,
// transparency chunk, interlacing, a damaged file) is left to OpenCV by returning an empty image,
// so callers always get exactly what cv::imread(path, cv::IMREAD_UNCHANGED) gives.
// Threads: any number of calls may run concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>

namespace cenote::io {

// Decodes a whole PNG file held in memory.
// @return CV_8UC1 (grey), CV_8UC3 (BGR) or CV_8UC4 (BGRA), the channel order of cv::imread; an
//   empty Mat when the file is not one of the handled kinds or cannot be decoded (never throws).
cv::Mat decodePngFast(const uint8_t* data, std::size_t size);

}  // namespace cenote::io
