#include "io/image/png_decoder.h"

#include <libdeflate.h>

#include <opencv2/imgproc.hpp>

#include <array>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string_view>
#include <vector>

#include "io/image/big_endian.h"

namespace cenote::io {
namespace {

// Chunks that do not change the pixels cv::imread returns (it applies no gamma, colour profile
// or background). Any other chunk sends the file to OpenCV.
bool isIgnorableChunk(std::string_view type) {
  for (std::string_view ok : {"tEXt", "zTXt", "iTXt", "pHYs", "tIME", "gAMA", "cHRM", "sRGB", "iCCP", "bKGD"}) {
    if (type == ok) return true;
  }
  return false;
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

// One decompressor per thread, kept between calls (it holds about 10 KB of tables).
libdeflate_decompressor* threadDecompressor() {
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> decompressor(libdeflate_alloc_decompressor());
  return decompressor.get();
}

uint8_t paeth(int left, int up, int up_left) {
  const int p = left + up - up_left;
  const int pa = std::abs(p - left), pb = std::abs(p - up), pc = std::abs(p - up_left);
  if (pa <= pb && pa <= pc) return static_cast<uint8_t>(left);
  return static_cast<uint8_t>(pb <= pc ? up : up_left);
}

// Sub filter: each byte adds the byte `kBpp` before it. The running pixel stays in registers; a
// byte loop through memory would wait on every previous store.
template <int kBpp>
void unfilterSub(const uint8_t* in, uint8_t* out, std::size_t length) {
  uint8_t left[kBpp] = {};
  for (std::size_t i = 0; i < length; i += kBpp) {
    for (int c = 0; c < kBpp; ++c) {
      left[c] = static_cast<uint8_t>(in[i + c] + left[c]);
      out[i + c] = left[c];
    }
  }
}

// Reverses the filter of one row (PNG specification, section 9) from `in` into `out`. `prev` is
// the previous row after unfiltering, or zeros for the first row. @return false for an unknown
// filter.
bool unfilterRow(int filter, const uint8_t* in, uint8_t* out, const uint8_t* prev, std::size_t length, int bpp) {
  switch (filter) {
    case 0: std::memcpy(out, in, length); return true;
    case 1:
      if (bpp == 1) unfilterSub<1>(in, out, length);
      if (bpp == 3) unfilterSub<3>(in, out, length);
      if (bpp == 4) unfilterSub<4>(in, out, length);
      return true;
    case 2:
      for (std::size_t i = 0; i < length; ++i) out[i] = static_cast<uint8_t>(in[i] + prev[i]);
      return true;
    case 3:
      for (std::size_t i = 0; i < length; ++i) {
        const int left = i >= static_cast<std::size_t>(bpp) ? out[i - bpp] : 0;
        out[i] = static_cast<uint8_t>(in[i] + ((left + prev[i]) >> 1));
      }
      return true;
    case 4:
      for (std::size_t i = 0; i < length; ++i) {
        const bool has_left = i >= static_cast<std::size_t>(bpp);
        out[i] = static_cast<uint8_t>(in[i] + paeth(has_left ? out[i - bpp] : 0, prev[i], has_left ? prev[i - bpp] : 0));
      }
      return true;
    default: return false;
  }
}

}  // namespace

cv::Mat decodePngFast(const uint8_t* data, std::size_t size) {
  if (size < kPngSignature.size() || std::memcmp(data, kPngSignature.data(), kPngSignature.size()) != 0) return {};
  std::size_t pos = kPngSignature.size();
  int width = 0, height = 0, channels = 0;
  thread_local std::vector<uint8_t> compressed;
  compressed.clear();
  bool seen_header = false, seen_end = false;
  while (!seen_end) {
    if (size - pos < 12) return {};
    const uint32_t length = loadBigEndian32(data + pos);
    if (length > size - pos - 12) return {};
    const std::string_view type(reinterpret_cast<const char*>(data + pos + 4), 4);
    const uint8_t* body = data + pos + 8;
    // The CRC covers the type and the body; libpng rejects a mismatch, and so do we (by deferring).
    if (libdeflate_crc32(0, data + pos + 4, length + 4) != loadBigEndian32(body + length)) return {};
    if (type == "IHDR") {
      if (length != 13 || seen_header) return {};
      const uint32_t w = loadBigEndian32(body), h = loadBigEndian32(body + 4);
      const int bit_depth = body[8], colour_type = body[9];
      const bool standard = body[10] == 0 && body[11] == 0 && body[12] == 0;  // deflate, filter set 0, not interlaced
      if (!standard || bit_depth != 8 || w == 0 || h == 0 || w > (1u << 15) || h > (1u << 15)) return {};
      channels = colour_type == 0 ? 1 : colour_type == 2 ? 3 : colour_type == 6 ? 4 : 0;
      if (channels == 0) return {};  // palette, grey + alpha
      width = static_cast<int>(w);
      height = static_cast<int>(h);
      seen_header = true;
    } else if (type == "IDAT") {
      if (!seen_header) return {};
      compressed.insert(compressed.end(), body, body + length);
    } else if (type == "IEND") {
      seen_end = true;
    } else if (!isIgnorableChunk(type)) {
      return {};
    }
    pos += 12 + length;
  }
  if (!seen_header || compressed.empty()) return {};

  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels;
  const std::size_t stride = row_bytes + 1;  // each row starts with its filter byte
  // Deflate inflates at most 1032:1 (image_header.h): a larger claim is a damaged file, refused
  // before the buffer for it is allocated.
  if (stride * height > 1032 * (compressed.size() + 1)) return {};
  // Reused per thread: a fresh buffer of this size would be page-faulted in for every frame.
  thread_local std::vector<uint8_t> raw;
  raw.resize(stride * height);
  libdeflate_decompressor* decompressor = threadDecompressor();
  if (!decompressor) return {};
  // A null actual size demands exactly raw.size() bytes: a short or long stream is an error.
  if (libdeflate_zlib_decompress(decompressor, compressed.data(), compressed.size(), raw.data(), raw.size(), nullptr) !=
      LIBDEFLATE_SUCCESS) {
    return {};
  }
  cv::Mat image(height, width, CV_MAKETYPE(CV_8U, channels));
  const std::vector<uint8_t> zeros(row_bytes, 0);
  const uint8_t* prev = zeros.data();
  for (int y = 0; y < height; ++y) {
    const uint8_t* in = raw.data() + y * stride;
    uint8_t* out = image.ptr<uint8_t>(y);
    if (!unfilterRow(in[0], in + 1, out, prev, row_bytes, channels)) return {};
    prev = out;
  }
  // RGB(A) -> BGR(A), OpenCV's order (in place, SIMD).
  if (channels == 3) cv::cvtColor(image, image, cv::COLOR_RGB2BGR);
  if (channels == 4) cv::cvtColor(image, image, cv::COLOR_RGBA2BGRA);
  return image;
}

}  // namespace cenote::io
