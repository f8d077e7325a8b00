#include "io/image/png_encoder.h"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "io/image/big_endian.h"
#include "io/image/rle_deflate.h"

namespace cenote::io {
namespace {

constexpr uint8_t kSubFilter = 1;

void appendBigEndian32(std::vector<uint8_t>& out, uint32_t value) {
  out.resize(out.size() + 4);
  storeBigEndian32(out.data() + out.size() - 4, value);
}

// Appends a chunk: length, type, body (what body(out) appends), CRC of type and body.
template <class Body>
void appendChunk(std::vector<uint8_t>& out, const char type[4], Body body) {
  const std::size_t start = out.size();
  appendBigEndian32(out, 0);
  out.insert(out.end(), type, type + 4);
  body(out);
  const std::size_t length = out.size() - start - 8;
  storeBigEndian32(out.data() + start, static_cast<uint32_t>(length));
  appendBigEndian32(out, libdeflate_crc32(0, out.data() + start + 4, length + 4));
}

// `image` in PNG's byte order: RGB(A) from OpenCV's BGR(A), 16-bit samples big-endian.
const cv::Mat& pngByteOrder(const cv::Mat& image) {
  thread_local cv::Mat converted;  // reused: a fresh image would be page-faulted in for every frame
  switch (image.type()) {
    case CV_8UC3: cv::cvtColor(image, converted, cv::COLOR_BGR2RGB); return converted;
    case CV_8UC4: cv::cvtColor(image, converted, cv::COLOR_BGRA2RGBA); return converted;
    case CV_16UC1:
      converted.create(image.size(), CV_16UC1);
      for (int y = 0; y < image.rows; ++y) {
        const uint16_t* in = image.ptr<uint16_t>(y);
        uint16_t* out = converted.ptr<uint16_t>(y);
        for (int x = 0; x < image.cols; ++x) out[x] = static_cast<uint16_t>(in[x] << 8 | in[x] >> 8);
      }
      return converted;
    default: return image;
  }
}

// The Sub filter (PNG specification, section 9.2): each byte minus the byte one pixel (bpp
// bytes) before it; `out` gets the filter type byte first.
void subFilterRow(const uint8_t* in, std::size_t length, std::size_t bpp, uint8_t* out) {
  *out++ = kSubFilter;
  std::memcpy(out, in, std::min(bpp, length));
  for (std::size_t i = bpp; i < length; ++i) out[i] = static_cast<uint8_t>(in[i] - in[i - bpp]);
}

}  // namespace

bool isPngEncodable(const cv::Mat& image) {
  const int type = image.type();
  const bool known = type == CV_8UC1 || type == CV_8UC3 || type == CV_8UC4 || type == CV_16UC1;
  // The image data goes into one IDAT chunk, whose length field holds less than 2^31 bytes: at most
  // 2^30 filtered bytes, which deflate (literal codes of at most 15 bits) cannot grow past it.
  const double filtered_bytes = (static_cast<double>(image.cols) * static_cast<double>(image.elemSize()) + 1.0) *
                                static_cast<double>(image.rows);
  return known && image.dims == 2 && image.rows > 0 && image.cols > 0 && filtered_bytes <= 0x1p30;
}

std::vector<uint8_t> encodePng(const cv::Mat& image) {
  if (!isPngEncodable(image)) return {};
  const cv::Mat& png_order = pngByteOrder(image);
  const std::size_t bpp = image.elemSize(), row_bytes = static_cast<std::size_t>(image.cols) * bpp;
  thread_local std::vector<uint8_t> filtered;  // reused, as in pngByteOrder
  filtered.resize((row_bytes + 1) * image.rows);
  for (int y = 0; y < image.rows; ++y) {
    subFilterRow(png_order.ptr<uint8_t>(y), row_bytes, bpp, filtered.data() + (row_bytes + 1) * y);
  }

  std::vector<uint8_t> file(kPngSignature.begin(), kPngSignature.end());
  appendChunk(file, "IHDR", [&](std::vector<uint8_t>& out) {
    appendBigEndian32(out, static_cast<uint32_t>(image.cols));
    appendBigEndian32(out, static_cast<uint32_t>(image.rows));
    const int channels = image.channels();
    out.push_back(image.depth() == CV_16U ? 16 : 8);           // bit depth
    out.push_back(channels == 1 ? 0 : channels == 3 ? 2 : 6);  // grey, RGB, RGBA
    out.insert(out.end(), {0, 0, 0});                          // deflate, filter method 0, not interlaced
  });
  appendChunk(file, "IDAT", [&](std::vector<uint8_t>& out) { deflateRle(filtered.data(), filtered.size(), out); });
  appendChunk(file, "IEND", [](std::vector<uint8_t>&) {});
  return file;
}

}  // namespace cenote::io
