// image_io.h: reading and writing the image files of the pipeline.
//   PFM: float32 maps (Middlebury's format: rows bottom to top, little-endian, +inf = invalid).
//   PNG/JPG: 8-bit images through OpenCV, with errors that name the file and the problem; PNGs of
//            8-bit grey, BGR, BGRA and 16-bit grey are read and written by png_decoder.h and
//            png_encoder.h (the same pixels, several times faster).
// Writes go to a temporary file renamed into place, so a crash never leaves half a file.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace cenote::io {

// @param image CV_32FC1 or CV_32FC3. @throws cenote::Error when the file cannot be written.
void writePfm(const std::string& path, const cv::Mat& image);

// @return CV_32FC1 or CV_32FC3. @throws cenote::Error when missing, truncated or not a PFM file.
cv::Mat readPfm(const std::string& path);

// 16-bit PNG of depth in millimetres (the TUM RGB-D convention): round(Z * 1000), 0 where the
// depth is not finite or <= 0. Depths above 65.535 m do not fit and are written as 0 as well.
// @param depth CV_32FC1 metres.
// @return the number of finite positive depths that did not fit (written as 0), for the caller to report.
// @throws cenote::Error when depth is not CV_32FC1 or the file cannot be written.
int writeDepthPng16(const std::string& path, const cv::Mat& depth);

// @return CV_32FC1 metres, +inf where the file holds 0.
// @throws cenote::Error when missing or not a 16-bit single-channel PNG.
cv::Mat readDepthPng16(const std::string& path);

// @param flags cv::IMREAD_* flags. A PNG or JPEG's header is read first (image_header.h): a size
// its compressed data cannot hold is refused before any pixel is allocated.
// @throws cenote::Error when missing or not a readable image (IoError "<path>: PNG claims ...").
cv::Mat readImage(const std::string& path, int flags);

// Decodes a PNG or JPEG held in memory, as cv::imdecode(IMREAD_UNCHANGED) would (8-bit grey, BGR
// or BGRA; 16-bit PNGs as 16-bit), but strictly: before any pixel is allocated it refuses another
// format (naming it), more than max_pixels, and a size the data cannot hold (image_header.h);
// then a truncated or corrupt file (PNG: a bad CRC, no IEND, a damaged zlib stream; JPEG: any
// libjpeg warning, jpeg_decoder.h).
// @param what names the image in errors ("left image", a path).
// @throws cenote::Error "<what>: ..." (ResourceExhaustedError beyond max_pixels).
cv::Mat decodeImageStrict(const uint8_t* data, std::size_t size, const std::string& what, uint64_t max_pixels);

// A JPEG of an 8-bit grey or BGR image at quality 1..100, in memory.
// @throws cenote::Error when the image cannot be encoded.
std::string encodeJpeg(const cv::Mat& image, int quality);

// @throws cenote::Error when the image cannot be encoded or written.
void writeImage(const std::string& path, const cv::Mat& image);

// Colour-mapped preview (turbo) of a float map over [min_value, max_value]; non-finite pixels
// black. When min_value >= max_value the range of the finite values is used.
cv::Mat colorizeMap(const cv::Mat& map, double min_value = 0.0, double max_value = 0.0);

}  // namespace cenote::io
