// png_decoder.h: fast decoding of the PNG files that stereo sequences are made of (8-bit grey,
// RGB or RGBA, not interlaced), inflated by ISA-L's igzip instead of zlib: inflating is most of a
// PNG's decoding time, and igzip inflates the simulator's noisy 800x600 frames in 0.26x zlib's
// time and 0.63x libdeflate's (bench/read_rectify_bench.cpp). Anything else (16-bit, palette,
// transparency chunk, interlacing, a damaged file) is left to OpenCV by returning an empty image,
// so callers always get exactly what cv::imread(path, cv::IMREAD_UNCHANGED) gives.
// Threads: any number of calls may run concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

namespace cenote::io {

// Whether the chunks' CRCs are to be checked, or were already (checkPngStructure, image_header.h,
// checks every one: readImage() and decodeImageStrict() call it first, and a frame's 800 KB need
// not be summed twice).
enum class ChunkCrc { kCheck, kAlreadyChecked };

// Decodes a whole PNG file held in memory.
// @return CV_8UC1 (grey), CV_8UC3 (BGR) or CV_8UC4 (BGRA), the channel order of cv::imread; an
//   empty Mat when the file is not one of the handled kinds or cannot be decoded (never throws).
//   Its memory is that of an image this thread decoded before and everyone has dropped, when
//   there is one of the size (mat_recycler.h): a stream of frames is not page-faulted in afresh.
cv::Mat decodePngFast(const uint8_t* data, std::size_t size, ChunkCrc crc = ChunkCrc::kCheck);

// What decodePngFast() reads before inflating: the image's size and channel count, and the zlib
// stream of its IDAT chunks (bench/read_rectify_bench.cpp inflates it with others). A stream in
// one chunk is read where it lies in the file; several are joined in `joined`.
struct PngImageData {
  int width = 0, height = 0, channels = 0;
  std::span<const uint8_t> zlib;  // into the file's bytes or into `joined`
  std::vector<uint8_t> joined;
};

// Reads the chunks of a PNG of a kind decodePngFast() handles into `out` (its buffer reused),
// checking every chunk's CRC unless told they were; out.zlib may point into `data`. @return false
// for any other file (never throws).
bool readPngImageData(const uint8_t* data, std::size_t size, PngImageData& out, ChunkCrc crc = ChunkCrc::kCheck);

}  // namespace cenote::io
