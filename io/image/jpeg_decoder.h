// jpeg_decoder.h: strict decoding of baseline and progressive JPEG files with libjpeg-turbo,
// to the pixels cv::imdecode(IMREAD_UNCHANGED) gives (grey: CV_8UC1; YCbCr or RGB: CV_8UC3 BGR;
// the same library and settings, so the same bytes), but where OpenCV lets libjpeg pad a file cut
// short with grey and go on, every libjpeg warning here is an error: a truncated file ("Premature
// end of JPEG file"), corrupt entropy-coded data ("Corrupt JPEG data: ..."), a bad Huffman code.
// A file of more than kMaxJpegScans scans is refused too (each progressive scan re-reads the whole
// image: a small file of many scans costs unbounded CPU).
// Threads: any number of calls may run concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace cenote::io {

inline constexpr int kMaxJpegScans = 256;

// @param what names the image in errors, e.g. "left image" or a file's path.
// @param max_pixels refused before any pixel is allocated when the frame header claims more.
// @throws cenote::Error "<what>: JPEG ..." with libjpeg's message for any error or warning, for a
//   CMYK / YCCK file (4 components; not a camera's), for 12-bit samples, more than max_pixels
//   (ResourceExhaustedError) or more than kMaxJpegScans scans.
cv::Mat decodeJpegStrict(const uint8_t* data, std::size_t size, const std::string& what, uint64_t max_pixels);

}  // namespace cenote::io
