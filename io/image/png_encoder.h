// png_encoder.h: fast encoding of the 8-bit and 16-bit images the pipeline writes (simulated
// frames, depth maps, previews) as standard PNG files. Every row uses the Sub filter (what
// OpenCV's encoder chooses for noisy camera images, and the cheapest to decode, png_decoder.h),
// and the deflate stream holds literals and runs only (rle_deflate.h): files about the size of
// OpenCV's, about 4 ms per noisy 800x600 colour image instead of 14 ms.
// Threads: any number of calls may run concurrently.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace cenote::io {

// Whether encodePng() takes this image: CV_8UC1, CV_8UC3 (BGR), CV_8UC4 (BGRA) or CV_16UC1,
// at least one pixel, at most 2^30 bytes of image data (one IDAT chunk).
bool isPngEncodable(const cv::Mat& image);

// The whole PNG file of `image` (grey, RGB or RGBA; 16-bit grey big-endian, as PNG stores it),
// decoded by cv::imread(IMREAD_UNCHANGED) to the same Mat. An image isPngEncodable() refuses
// gives an empty vector.
std::vector<uint8_t> encodePng(const cv::Mat& image);

}  // namespace cenote::io
