// image_header.h: what a PNG or JPEG file says about its image, read before a single pixel is
// decoded, so that a reader can refuse a size it will not hold (a few KB of PNG can claim
// 2^31 x 2^31 pixels) without allocating it. Only PNG and JPEG are recognised; anything else is
// named by its signature (GIF, BMP, TIFF, WebP, ...) in the error.
//   PNG: the IHDR chunk (the first chunk, CRC checked): width, height, bit depth, colour type.
//   JPEG: the segments from SOI up to the first SOFn frame header: precision, height, width,
//         number of components.
// Also the most pixels the file's compressed data can hold: a deflate stream inflates at most
// 1032:1 (a 258-byte match in 2 bits), and a Huffman-coded JPEG spends at least one bit on the DC
// coefficient of every 8x8 block, so a file that claims more is corrupt whatever it says.
// Threads: pure functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace cenote::io {

enum class EncodedFormat { kPng, kJpeg };

// "PNG", "JPEG".
const char* toString(EncodedFormat format);

struct ImageHeader {
  EncodedFormat format = EncodedFormat::kPng;
  uint32_t width = 0;
  uint32_t height = 0;
  int bit_depth = 0;         // bits per sample: PNG 1, 2, 4, 8 or 16; JPEG 8 or 12
  int channels = 0;          // samples per pixel in the file: PNG grey 1, grey+alpha 2, RGB 3, RGBA 4,
                             // palette 1 (index); JPEG components (1 grey, 3 YCbCr, 4 CMYK)
  bool interlaced = false;   // PNG Adam7
  bool arithmetic = false;   // JPEG arithmetic coding (SOF9..SOF15): no bound on its compression
  uint64_t data_bytes = 0;   // PNG: the bytes of all IDAT chunks (0 until checkPngStructure);
                             // JPEG: the bytes after the frame header
  uint64_t jpeg_blocks = 0;  // JPEG: the 8x8 blocks of all components, from the sampling factors

  uint64_t pixels() const { return uint64_t{width} * height; }
  // PNG: the bytes of the inflated image (rows with their filter byte; a lower bound when interlaced).
  uint64_t pngInflatedBytes() const;
  // Whether data_bytes can hold the image by the bounds above (always true for arithmetic JPEG).
  bool dataCanHold() const;
};

// The format of the file's first bytes: PNG, JPEG, or a name for the error ("GIF", "BMP", "TIFF",
// "WebP", "PPM", "PFM", "an unknown format (first bytes 47 49 ...)"); "no data" for size 0.
std::string describeFormat(const uint8_t* data, std::size_t size);

// @param what names the image in errors, e.g. "left image" or a file's path.
// @throws cenote::Error (kInvalidArgument) "<what>: ..." when the data is not PNG or JPEG (naming
//   the format it is), or its header is truncated, damaged (bad IHDR CRC), or gives a zero width
//   or height (JPEG: height defined later by DNL is refused).
ImageHeader readImageHeader(const uint8_t* data, std::size_t size, const std::string& what);

// The whole structure of a PNG file: every chunk within the file with a correct CRC, IHDR first,
// at least one IDAT, IEND at the end, and IDAT bytes enough to inflate to the IHDR's size.
// @return the header with data_bytes set.
// @throws cenote::Error "<what>: ..." naming the chunk and what is wrong ("truncated in chunk IDAT",
//   "no IEND chunk: the file is cut short", "chunk IDAT has a bad CRC", "claims 40000x40000 pixels
//   but its 120 bytes of IDAT inflate to at most ...").
ImageHeader checkPngStructure(const uint8_t* data, std::size_t size, const std::string& what);

}  // namespace cenote::io
