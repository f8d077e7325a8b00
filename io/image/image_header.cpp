#include "io/image/image_header.h"

#include <libdeflate.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string_view>

#include "common/error.h"
#include "io/image/big_endian.h"

namespace cenote::io {
namespace {

using namespace std::string_view_literals;

constexpr uint64_t kMaxInflateRatio = 1032;   // deflate: a 258-byte match (code 285, distance 1) in 2 bits
constexpr uint64_t kMinBitsPerJpegBlock = 1;  // Huffman: the shortest code of a block's DC difference

bool startsWith(const uint8_t* data, std::size_t size, std::string_view prefix) {
  return size >= prefix.size() && std::memcmp(data, prefix.data(), prefix.size()) == 0;
}

uint32_t load16(const uint8_t* p) { return (uint32_t{p[0]} << 8) | p[1]; }

std::string sizeText(uint32_t w, uint32_t h) { return std::to_string(w) + "x" + std::to_string(h); }

ImageHeader readPngHeader(const uint8_t* data, std::size_t size, const std::string& what) {
  // Signature (8), then the IHDR chunk: length (4), type (4), body (13), CRC (4).
  if (size < 33) throw Error(what + ": PNG of " + std::to_string(size) + " bytes is too short for its IHDR header");
  const uint8_t* chunk = data + kPngSignature.size();
  if (loadBigEndian32(chunk) != 13 || std::memcmp(chunk + 4, "IHDR", 4) != 0) {
    throw Error(what + ": PNG does not start with an IHDR chunk of 13 bytes");
  }
  if (libdeflate_crc32(0, chunk + 4, 17) != loadBigEndian32(chunk + 21)) throw Error(what + ": PNG IHDR has a bad CRC");
  const uint8_t* body = chunk + 8;
  ImageHeader h;
  h.format = EncodedFormat::kPng;
  h.width = loadBigEndian32(body);
  h.height = loadBigEndian32(body + 4);
  h.bit_depth = body[8];
  const int colour_type = body[9];
  h.interlaced = body[12] == 1;
  switch (colour_type) {
    case 0: h.channels = 1; break;
    case 2: h.channels = 3; break;
    case 3: h.channels = 1; break;
    case 4: h.channels = 2; break;
    case 6: h.channels = 4; break;
    default: throw Error(what + ": PNG colour type " + std::to_string(colour_type) + " does not exist (0, 2, 3, 4 or 6)");
  }
  const int depth = h.bit_depth;
  const bool depth_ok = colour_type == 0   ? (depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16)
                        : colour_type == 3 ? (depth == 1 || depth == 2 || depth == 4 || depth == 8)
                                           : (depth == 8 || depth == 16);
  if (!depth_ok) {
    throw Error(what + ": PNG bit depth " + std::to_string(depth) + " is not allowed for colour type " +
                std::to_string(colour_type));
  }
  if (body[10] != 0 || body[11] != 0 || body[12] > 1) {
    throw Error(what + ": PNG IHDR has an unknown compression, filter or interlace method");
  }
  // The PNG specification limits both to 2^31 - 1.
  if (h.width == 0 || h.height == 0 || h.width > 0x7FFFFFFFu || h.height > 0x7FFFFFFFu) {
    throw Error(what + ": PNG IHDR gives the size " + sizeText(h.width, h.height) + " (each side in [1, 2^31 - 1])");
  }
  return h;
}

bool isSofMarker(int m) { return m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC; }

ImageHeader readJpegHeader(const uint8_t* data, std::size_t size, const std::string& what) {
  std::size_t pos = 2;  // after SOI
  while (true) {
    if (pos >= size || data[pos] != 0xFF) {
      throw Error(what + ": JPEG ends or has no marker at byte " + std::to_string(pos) + " before its frame header (SOF)");
    }
    while (pos < size && data[pos] == 0xFF) ++pos;  // fill bytes
    if (pos >= size) throw Error(what + ": JPEG is cut short before its frame header (SOF)");
    const int marker = data[pos++];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // TEM, RSTn: no length
    if (marker == 0xD8 || marker == 0xD9 || marker == 0xDA || marker == 0x00) {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "%02X", marker);
      throw Error(what + ": JPEG has marker FF" + hex + " before its frame header (SOF)");
    }
    if (size - pos < 2) throw Error(what + ": JPEG is cut short in a segment header");
    const uint32_t length = load16(data + pos);
    if (length < 2 || length > size - pos) {
      throw Error(what + ": JPEG segment at byte " + std::to_string(pos - 2) + " claims " + std::to_string(length) +
                  " bytes, more than the file holds");
    }
    if (!isSofMarker(marker)) {
      pos += length;
      continue;
    }
    const uint8_t* sof = data + pos + 2;
    if (length < 8) throw Error(what + ": JPEG frame header (SOF) of " + std::to_string(length) + " bytes is too short");
    ImageHeader h;
    h.format = EncodedFormat::kJpeg;
    h.bit_depth = sof[0];
    h.height = load16(sof + 1);
    h.width = load16(sof + 3);
    h.channels = sof[5];
    h.arithmetic = marker >= 0xC9;
    if (h.channels == 0 || length != 8 + 3 * static_cast<uint32_t>(h.channels)) {
      throw Error(what + ": JPEG frame header (SOF) of " + std::to_string(length) + " bytes does not fit its " +
                  std::to_string(h.channels) + " components");
    }
    if (h.width == 0 || h.height == 0) {
      throw Error(what + ": JPEG frame header gives the size " + sizeText(h.width, h.height) +
                  " (a height given later by a DNL marker is not supported)");
    }
    int h_max = 1, v_max = 1;
    for (int c = 0; c < h.channels; ++c) {
      const int hs = sof[7 + 3 * c] >> 4, vs = sof[7 + 3 * c] & 15;
      if (hs < 1 || hs > 4 || vs < 1 || vs > 4) throw Error(what + ": JPEG component has sampling factors outside [1, 4]");
      h_max = std::max(h_max, hs);
      v_max = std::max(v_max, vs);
    }
    for (int c = 0; c < h.channels; ++c) {
      const uint64_t hs = sof[7 + 3 * c] >> 4, vs = sof[7 + 3 * c] & 15;
      const uint64_t cols = (h.width * hs + h_max - 1) / h_max, rows = (h.height * vs + v_max - 1) / v_max;
      h.jpeg_blocks += ((cols + 7) / 8) * ((rows + 7) / 8);
    }
    h.data_bytes = size - pos - length;
    return h;
  }
}

}  // namespace

const char* toString(EncodedFormat format) { return format == EncodedFormat::kPng ? "PNG" : "JPEG"; }

uint64_t ImageHeader::pngInflatedBytes() const {
  const uint64_t row_bits = uint64_t{width} * static_cast<uint64_t>(channels) * static_cast<uint64_t>(bit_depth);
  return uint64_t{height} * (1 + (row_bits + 7) / 8);
}

bool ImageHeader::dataCanHold() const {
  if (format == EncodedFormat::kPng) return pngInflatedBytes() <= kMaxInflateRatio * (data_bytes + 1);
  if (arithmetic) return true;
  return jpeg_blocks * kMinBitsPerJpegBlock <= 8 * data_bytes;
}

std::string describeFormat(const uint8_t* data, std::size_t size) {
  if (size == 0) return "no data";
  if (startsWith(data, size, std::string_view(reinterpret_cast<const char*>(kPngSignature.data()), 8))) return "PNG";
  if (startsWith(data, size, "\xFF\xD8\xFF")) return "JPEG";
  if (startsWith(data, size, "GIF8")) return "GIF";
  if (startsWith(data, size, "BM")) return "BMP";
  if (startsWith(data, size, "II*") || startsWith(data, size, "MM\0*"sv)) return "TIFF";
  if (startsWith(data, size, "RIFF") && size >= 12 && std::memcmp(data + 8, "WEBP", 4) == 0) return "WebP";
  if (startsWith(data, size, "\0\0\0\x0CjP  "sv) || startsWith(data, size, "\xFF\x4F\xFF\x51")) return "JPEG 2000";
  if (startsWith(data, size, "#?RADIANCE") || startsWith(data, size, "#?RGBE")) return "Radiance HDR";
  if (startsWith(data, size, "v/1\x01")) return "OpenEXR";
  if (startsWith(data, size, "Pf") || startsWith(data, size, "PF")) return "PFM";
  if (size >= 2 && data[0] == 'P' && data[1] >= '1' && data[1] <= '7') return "PNM";
  std::string bytes;
  for (std::size_t i = 0; i < std::min<std::size_t>(size, 4); ++i) {
    char hex[4];
    std::snprintf(hex, sizeof(hex), "%s%02X", i == 0 ? "" : " ", data[i]);
    bytes += hex;
  }
  return "an unknown format (first bytes " + bytes + ")";
}

ImageHeader readImageHeader(const uint8_t* data, std::size_t size, const std::string& what) {
  const std::string format = describeFormat(data, size);
  if (format == "PNG") return readPngHeader(data, size, what);
  if (format == "JPEG") return readJpegHeader(data, size, what);
  throw Error(what + ": " + (size == 0 ? std::string("no image data") : format + " is not accepted, only PNG and JPEG"));
}

ImageHeader checkPngStructure(const uint8_t* data, std::size_t size, const std::string& what) {
  ImageHeader h = readPngHeader(data, size, what);
  std::size_t pos = kPngSignature.size();
  bool seen_idat = false;
  while (true) {
    if (size - pos < 12) {
      throw Error(what + ": PNG has no IEND chunk: the file is cut short after " + std::to_string(pos) + " bytes");
    }
    const uint32_t length = loadBigEndian32(data + pos);
    const std::string type(reinterpret_cast<const char*>(data + pos + 4), 4);
    if (length > size - pos - 12) {
      throw Error(what + ": PNG is truncated in chunk " + type + " (" + std::to_string(length) + " bytes announced, " +
                  std::to_string(size - pos - 12) + " left)");
    }
    if (libdeflate_crc32(0, data + pos + 4, length + 4) != loadBigEndian32(data + pos + 8 + length)) {
      throw Error(what + ": PNG chunk " + type + " at byte " + std::to_string(pos) + " has a bad CRC");
    }
    pos += 12 + length;
    if (type == "IDAT") {
      seen_idat = true;
      h.data_bytes += length;
    } else if (type == "IEND") {
      break;
    } else if (type == "IHDR" && pos != kPngSignature.size() + 25) {
      throw Error(what + ": PNG has a second IHDR chunk");
    }
  }
  if (!seen_idat) throw Error(what + ": PNG has no IDAT chunk (no pixels)");
  if (!h.dataCanHold()) {
    throw Error(what + ": PNG claims " + sizeText(h.width, h.height) + " pixels, " + std::to_string(h.pngInflatedBytes()) +
                " bytes inflated, but its " + std::to_string(h.data_bytes) + " bytes of IDAT inflate to at most " +
                std::to_string(kMaxInflateRatio * (h.data_bytes + 1)));
  }
  return h;
}

}  // namespace cenote::io
