#include "io/image/image_io.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <span>
#include <sstream>

#include "common/atomic_file.h"
#include "common/error.h"
#include "io/image/image_header.h"
#include "io/image/jpeg_decoder.h"
#include "io/image/opencv_codecs.h"
#include "io/image/png_decoder.h"
#include "io/image/png_encoder.h"

namespace cenote::io {
namespace {

// @param what names the image in errors ("a JPEG", a path).
std::vector<uint8_t> encodeWithOpenCv(const std::string& ext, const cv::Mat& image, const std::vector<int>& params,
                                      const std::string& what) {
  std::vector<uint8_t> bytes;
  bool ok = false;
  try {
    ok = opencvEncode(ext, image, bytes, params);
  } catch (const cv::Exception& e) {
    throw Error("cannot encode " + what + ": " + e.what());
  }
  if (!ok) throw Error("cannot encode " + what);
  return bytes;
}

constexpr double kMillimetresPerMetre = 1000.0;  // 16-bit depth PNGs store millimetres

}  // namespace

void writePfm(const std::string& path, const cv::Mat& image) {
  if (image.type() != CV_32FC1 && image.type() != CV_32FC3) {
    throw Error("writePfm " + path + ": image must be CV_32FC1 or CV_32FC3");
  }
  // Per-frame output (depth maps of every frame): no fsync (common/atomic_file.h).
  writeAtomically(path, Durability::kFast, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throwWriteError(path, "cannot create file", errno);
    const int channels = image.channels();
    out << (channels == 3 ? "PF" : "Pf") << "\n" << image.cols << " " << image.rows << "\n-1\n";
    for (int y = image.rows - 1; y >= 0; --y) {
      out.write(reinterpret_cast<const char*>(image.ptr<float>(y)),
                static_cast<std::streamsize>(image.cols) * channels * sizeof(float));
    }
    out.close();
    if (!out) throwWriteError(path, "write failed (disk full?)", errno);
  });
}

cv::Mat readPfm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throwReadError(path);
  std::string magic;
  int width = 0, height = 0;
  double scale = 0.0;
  in >> magic >> width >> height >> scale;
  if (!in || (magic != "Pf" && magic != "PF")) throw Error(path + ": not a PFM file (bad header)");
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536 || scale == 0.0) {
    throw Error(path + ": PFM header has invalid size or scale");
  }
  in.get();  // the single whitespace after the scale
  const int channels = magic == "PF" ? 3 : 1;
  cv::Mat image(height, width, channels == 3 ? CV_32FC3 : CV_32FC1);
  const bool swap = scale > 0.0;  // positive scale = big-endian data
  for (int y = height - 1; y >= 0; --y) {
    in.read(reinterpret_cast<char*>(image.ptr<float>(y)), static_cast<std::streamsize>(width) * channels * sizeof(float));
    if (!in) throw Error(path + ": PFM file is truncated");
    if (swap) {
      uint32_t* words = image.ptr<uint32_t>(y);
      for (int i = 0; i < width * channels; ++i) words[i] = __builtin_bswap32(words[i]);
    }
  }
  return image;
}

int writeDepthPng16(const std::string& path, const cv::Mat& depth) {
  if (depth.type() != CV_32FC1) throw Error("writeDepthPng16 " + path + ": depth must be CV_32FC1 (metres)");
  cv::Mat millimetres(depth.size(), CV_16UC1);
  int clipped = 0;
  for (int y = 0; y < depth.rows; ++y) {
    const float* in = depth.ptr<float>(y);
    uint16_t* out = millimetres.ptr<uint16_t>(y);
    for (int x = 0; x < depth.cols; ++x) {
      const double mm = std::round(in[x] * kMillimetresPerMetre);
      const bool valid = std::isfinite(in[x]) && in[x] > 0.0f;
      const bool fits = mm <= std::numeric_limits<uint16_t>::max();
      clipped += valid && !fits;
      out[x] = valid && fits ? static_cast<uint16_t>(mm) : 0;
    }
  }
  writeImage(path, millimetres);
  return clipped;
}

cv::Mat readDepthPng16(const std::string& path) {
  const cv::Mat raw = readImage(path, cv::IMREAD_UNCHANGED);
  if (raw.type() != CV_16UC1) throw Error(path + ": not a 16-bit single-channel depth PNG");
  cv::Mat depth(raw.size(), CV_32FC1);
  for (int y = 0; y < raw.rows; ++y) {
    const uint16_t* in = raw.ptr<uint16_t>(y);
    float* out = depth.ptr<float>(y);
    for (int x = 0; x < raw.cols; ++x) {
      out[x] = in[x] == 0 ? std::numeric_limits<float>::infinity() : static_cast<float>(in[x] / kMillimetresPerMetre);
    }
  }
  return depth;
}

cv::Mat readImage(const std::string& path, int flags) {
  if (!std::filesystem::exists(path)) throw NotFoundError("cannot read image " + path + ": no such file");
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const std::size_t size = in ? static_cast<std::size_t>(in.tellg()) : 0;
  // Not zero-filled first: every byte is read over (a frame's PNG is about 800 KB, twice a frame).
  const std::unique_ptr<uint8_t[]> buffer = std::make_unique_for_overwrite<uint8_t[]>(size);
  const std::span<const uint8_t> bytes(buffer.get(), size);
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(buffer.get()), static_cast<std::streamsize>(size))) {
    throw IoError("cannot read image " + path + ": read failed");
  }
  // The size a PNG or JPEG claims, checked against what its data can hold before decoding.
  const std::string format = describeFormat(bytes.data(), bytes.size());
  if (format == "PNG") {
    try {
      checkPngStructure(bytes.data(), bytes.size(), path);
    } catch (const Error& e) {
      throw IoError(std::string("cannot read image ") + e.what());
    }
  } else if (format == "JPEG") {
    ImageHeader header;
    try {
      header = readImageHeader(bytes.data(), bytes.size(), path);
    } catch (const Error& e) {
      throw IoError(std::string("cannot read image ") + e.what());
    }
    if (!header.dataCanHold()) {
      throw IoError("cannot read image " + path + ": JPEG claims " + std::to_string(header.width) + "x" +
                    std::to_string(header.height) + " pixels, more than its " + std::to_string(header.data_bytes) +
                    " bytes of data can hold");
    }
  }
  // 8-bit PNGs (what stereo sequences are made of) through our decoder; everything else, and any
  // PNG it does not handle, through OpenCV. Both give the same pixels.
  if (flags == cv::IMREAD_UNCHANGED || flags == cv::IMREAD_COLOR) {
    cv::Mat fast = decodePngFast(bytes.data(), bytes.size(),
                                 format == "PNG" ? ChunkCrc::kAlreadyChecked : ChunkCrc::kCheck);
    if (!fast.empty() && (flags == cv::IMREAD_UNCHANGED || fast.channels() == 3)) return fast;
  }
  cv::Mat image = opencvDecode(bytes.data(), bytes.size(), flags);
  if (image.empty()) throw Error("cannot read image " + path + ": not a readable image file");
  return image;
}

cv::Mat decodeImageStrict(const uint8_t* data, std::size_t size, const std::string& what, uint64_t max_pixels) {
  const ImageHeader header = readImageHeader(data, size, what);
  if (header.pixels() > max_pixels) {
    throw ResourceExhaustedError(what + ": " + toString(header.format) + " of " + std::to_string(header.width) + "x" +
                                 std::to_string(header.height) + " = " + std::to_string(header.pixels()) +
                                 " pixels, more than the limit of " + std::to_string(max_pixels));
  }
  if (header.format == EncodedFormat::kJpeg) {
    if (!header.dataCanHold()) {
      throw Error(what + ": JPEG claims " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                  " pixels, more than its " + std::to_string(header.data_bytes) + " bytes of data can hold");
    }
    return decodeJpegStrict(data, size, what, max_pixels);
  }
  checkPngStructure(data, size, what);
  cv::Mat image = decodePngFast(data, size, ChunkCrc::kAlreadyChecked);
  if (!image.empty()) return image;
  // Kinds the fast decoder leaves to OpenCV (16-bit, palette, interlaced); libpng checks the zlib
  // stream and the amount of image data.
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw ResourceExhaustedError(what + ": PNG of " + std::to_string(size) + " bytes, more than OpenCV takes (2^31 - 1)");
  }
  try {
    image = opencvDecode(data, size, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw Error(what + ": PNG cannot be decoded: " + e.what());
  }
  if (image.empty()) throw Error(what + ": PNG cannot be decoded: its compressed image data is damaged");
  return image;
}

std::string encodeJpeg(const cv::Mat& image, int quality) {
  const std::vector<uint8_t> bytes = encodeWithOpenCv(".jpg", image, {cv::IMWRITE_JPEG_QUALITY, quality}, "a JPEG");
  return std::string(bytes.begin(), bytes.end());
}

void writeImage(const std::string& path, const cv::Mat& image) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.empty()) ext = ".png";
  std::vector<uint8_t> bytes;
  // PNGs through our own encoder where it takes the image (a quarter of OpenCV's time), anything
  // else through OpenCV.
  const bool png = ext == ".png" || ext == ".PNG";
  if (png && isPngEncodable(image)) {
    bytes = encodePng(image);
  } else {
    bytes = encodeWithOpenCv(ext, image, {}, path);
  }
  // Per-frame output (images and depth PNGs of every frame): no fsync (common/atomic_file.h).
  writeFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), Durability::kFast);
}

cv::Mat colorizeMap(const cv::Mat& map, double min_value, double max_value) {
  if (map.type() != CV_32FC1) throw Error("colorizeMap: map must be CV_32FC1");
  if (min_value >= max_value) {
    min_value = std::numeric_limits<double>::max();
    max_value = std::numeric_limits<double>::lowest();
    for (int y = 0; y < map.rows; ++y) {
      const float* row = map.ptr<float>(y);
      for (int x = 0; x < map.cols; ++x) {
        if (!std::isfinite(row[x])) continue;
        min_value = std::min<double>(min_value, row[x]);
        max_value = std::max<double>(max_value, row[x]);
      }
    }
    if (min_value >= max_value) max_value = min_value + 1.0;
  }
  cv::Mat scaled(map.size(), CV_8UC1), valid(map.size(), CV_8UC1);
  const double scale = 255.0 / (max_value - min_value);
  for (int y = 0; y < map.rows; ++y) {
    const float* row = map.ptr<float>(y);
    uint8_t* s = scaled.ptr<uint8_t>(y);
    uint8_t* v = valid.ptr<uint8_t>(y);
    for (int x = 0; x < map.cols; ++x) {
      v[x] = std::isfinite(row[x]) ? 255 : 0;
      s[x] = v[x] ? cv::saturate_cast<uint8_t>((row[x] - min_value) * scale) : 0;
    }
  }
  cv::Mat colour;
  cv::applyColorMap(scaled, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar::all(0), valid == 0);
  return colour;
}

}  // namespace cenote::io
