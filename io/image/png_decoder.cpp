#include "io/image/png_decoder.h"

#include "io/compression/igzip_inflate.h"

#include <libdeflate.h>

#include <opencv2/imgproc.hpp>

#include <array>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string_view>
#include <vector>

#include "io/image/big_endian.h"
#include "io/image/mat_recycler.h"
#include "io/image/png_unfilter.h"

namespace cenote::io {
namespace {

// Decoded images kept for reuse per thread: what `cenote run` holds at once (both images of the
// frames in its queues, the left ones of the fusion window's views), and a few more.
constexpr std::size_t kRecycledImages = 16;

// Chunks that do not change the pixels cv::imread returns (it applies no gamma, colour profile
// or background). Any other chunk sends the file to OpenCV.
bool isIgnorableChunk(std::string_view type) {
  for (std::string_view ok : {"tEXt", "zTXt", "iTXt", "pHYs", "tIME", "gAMA", "cHRM", "sRGB", "iCCP", "bKGD"}) {
    if (type == ok) return true;
  }
  return false;
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

// Reverses the filter of one row (PNG specification, section 9) from `in` into `out`, which may be
// `in` itself (each byte depends only on bytes before it and on `prev`). `prev` is
// the previous row after unfiltering, or zeros for the first row. @return false for an unknown
// filter.
bool unfilterRow(int filter, const uint8_t* in, uint8_t* out, const uint8_t* prev, std::size_t length, int bpp) {
  switch (filter) {
    case 0:
      if (out != in) std::memcpy(out, in, length);
      return true;
    case 1:
      if (bpp == 1) unfilterSub<1>(in, out, length);
      if (bpp == 3) detail::unfilterSubRgb(in, out, length);
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

bool readPngImageData(const uint8_t* data, std::size_t size, PngImageData& out, ChunkCrc crc) {
  if (size < kPngSignature.size() || std::memcmp(data, kPngSignature.data(), kPngSignature.size()) != 0) return false;
  std::size_t pos = kPngSignature.size();
  out.zlib = {};
  out.joined.clear();
  int idat_chunks = 0;
  bool seen_header = false, seen_end = false;
  while (!seen_end) {
    if (size - pos < 12) return false;
    const uint32_t length = loadBigEndian32(data + pos);
    if (length > size - pos - 12) return false;
    const std::string_view type(reinterpret_cast<const char*>(data + pos + 4), 4);
    const uint8_t* body = data + pos + 8;
    // The CRC covers the type and the body; libpng rejects a mismatch, and so do we (by deferring).
    if (crc == ChunkCrc::kCheck && libdeflate_crc32(0, data + pos + 4, length + 4) != loadBigEndian32(body + length)) {
      return false;
    }
    if (type == "IHDR") {
      if (length != 13 || seen_header) return false;
      const uint32_t w = loadBigEndian32(body), h = loadBigEndian32(body + 4);
      const int bit_depth = body[8], colour_type = body[9];
      const bool standard = body[10] == 0 && body[11] == 0 && body[12] == 0;  // deflate, filter set 0, not interlaced
      if (!standard || bit_depth != 8 || w == 0 || h == 0 || w > (1u << 15) || h > (1u << 15)) return false;
      out.channels = colour_type == 0 ? 1 : colour_type == 2 ? 3 : colour_type == 6 ? 4 : 0;
      if (out.channels == 0) return false;  // palette, grey + alpha
      out.width = static_cast<int>(w);
      out.height = static_cast<int>(h);
      seen_header = true;
    } else if (type == "IDAT") {
      if (!seen_header) return false;
      // The first chunk is read in place; a second one starts the joined copy.
      if (++idat_chunks == 1) out.zlib = {body, length};
      if (idat_chunks == 2) out.joined.assign(out.zlib.begin(), out.zlib.end());
      if (idat_chunks >= 2) out.joined.insert(out.joined.end(), body, body + length);
    } else if (type == "IEND") {
      seen_end = true;
    } else if (!isIgnorableChunk(type)) {
      return false;
    }
    pos += 12 + length;
  }
  if (idat_chunks >= 2) out.zlib = out.joined;
  return seen_header && !out.zlib.empty() && out.zlib.size() <= UINT32_MAX;
}

cv::Mat decodePngFast(const uint8_t* data, std::size_t size, ChunkCrc crc) {
  thread_local PngImageData png;  // its buffer for joined chunks reused from frame to frame
  if (!readPngImageData(data, size, png, crc)) return {};
  const int width = png.width, height = png.height, channels = png.channels;
  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels;
  const std::size_t stride = row_bytes + 1;  // each row starts with its filter byte
  // Deflate inflates at most 1032:1 (image_header.h): a larger claim is a damaged file, refused
  // before the buffer for it is allocated.
  if (stride * height > 1032 * (png.zlib.size() + 1)) return {};
  // Reused per thread: a fresh buffer of this size would be page-faulted in for every frame.
  thread_local std::vector<uint8_t> raw;
  raw.resize(stride * height);
  if (!inflateExactly(png.zlib, raw.data(), raw.size(), DeflateWrapper::kZlib)) return {};
  // Rows are unfiltered in place (a row's filter reads only bytes before it, already unfiltered),
  // then copied out once: for colour, by the RGB(A) -> BGR(A) conversion into OpenCV's order.
  const std::vector<uint8_t> zeros(row_bytes, 0);
  const uint8_t* prev = zeros.data();
  for (int y = 0; y < height; ++y) {
    uint8_t* row = raw.data() + y * stride;
    if (!unfilterRow(row[0], row + 1, row + 1, prev, row_bytes, channels)) return {};
    prev = row + 1;
  }
  const cv::Mat unfiltered(height, width, CV_MAKETYPE(CV_8U, channels), raw.data() + 1, stride);
  // A stereo run's frames are all of one size and a pipeline holds a few of them at once (queues,
  // the fusion window): their memory is reused once they are dropped (mat_recycler.h).
  thread_local MatRecycler images(kRecycledImages);
  cv::Mat image = images.take(height, width, unfiltered.type());
  if (channels == 1) unfiltered.copyTo(image);
  if (channels == 3) cv::cvtColor(unfiltered, image, cv::COLOR_RGB2BGR);
  if (channels == 4) cv::cvtColor(unfiltered, image, cv::COLOR_RGBA2BGRA);
  return image;
}

}  // namespace cenote::io
