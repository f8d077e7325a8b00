#include "eval/depth/colmap_depth_io.h"

#include <bit>
#include <filesystem>
#include <fstream>
#include <vector>

#include "common/error.h"

namespace cenote::eval {
namespace {

static_assert(std::endian::native == std::endian::little, "COLMAP arrays are little-endian");

constexpr long kMaxSide = 1 << 16;  // larger sides mean a corrupt header, not a camera
constexpr long kMaxChannels = 16;

long parseField(std::istream& in, const std::string& path, const char* what) {
  std::string digits;
  char c = 0;
  while (in.get(c) && c != '&') {
    if (c < '0' || c > '9' || digits.size() > 9) {
      throw Error(path + ": not a COLMAP array (header must be 'WIDTH&HEIGHT&CHANNELS&', bad " + what + ")");
    }
    digits += c;
  }
  if (c != '&' || digits.empty()) {
    throw Error(path + ": not a COLMAP array (header must be 'WIDTH&HEIGHT&CHANNELS&', no " + what + ")");
  }
  return std::stol(digits);
}

}  // namespace

cv::Mat readColmapArray(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throwReadError(path);
  }
  const long width = parseField(in, path, "width");
  const long height = parseField(in, path, "height");
  const long channels = parseField(in, path, "channels");
  if (width <= 0 || height <= 0 || channels <= 0 || width > kMaxSide || height > kMaxSide || channels > kMaxChannels) {
    throw Error(path + ": COLMAP array header " + std::to_string(width) + "&" + std::to_string(height) + "&" +
                std::to_string(channels) + "& is out of range (sides 1.." + std::to_string(kMaxSide) + ", channels 1.." +
                std::to_string(kMaxChannels) + ")");
  }
  const size_t plane = static_cast<size_t>(width) * height;
  std::vector<float> data(plane * channels);
  in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(float)));
  const auto got = static_cast<size_t>(in.gcount());
  if (got != data.size() * sizeof(float)) {
    throw Error(path + ": COLMAP array is truncated (" + std::to_string(width) + "x" + std::to_string(height) + "x" +
                std::to_string(channels) + " floats announced, " + std::to_string(got) + " bytes of data)");
  }
  if (in.peek() != std::char_traits<char>::eof()) {
    throw Error(path + ": COLMAP array has data past the " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                std::to_string(channels) + " floats its header announces");
  }
  cv::Mat result(static_cast<int>(height), static_cast<int>(width), CV_32FC(static_cast<int>(channels)));
  for (long y = 0; y < height; ++y) {
    float* row = result.ptr<float>(static_cast<int>(y));
    for (long x = 0; x < width; ++x) {
      for (long c = 0; c < channels; ++c) row[x * channels + c] = data[x + width * y + plane * c];
    }
  }
  return result;
}

void writeColmapArray(const std::string& path, const cv::Mat& array) {
  if (array.depth() != CV_32F || array.empty())
    throw Error("writeColmapArray " + path + ": array must be non-empty float32");
  const int channels = array.channels();
  const size_t plane = static_cast<size_t>(array.cols) * array.rows;
  std::vector<float> data(plane * channels);
  for (int y = 0; y < array.rows; ++y) {
    const float* row = array.ptr<float>(y);
    for (int x = 0; x < array.cols; ++x) {
      for (int c = 0; c < channels; ++c) data[x + static_cast<size_t>(array.cols) * y + plane * c] = row[x * channels + c];
    }
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw Error("cannot write " + path + ": cannot create file");
  out << array.cols << "&" << array.rows << "&" << channels << "&";
  out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(float)));
  out.close();
  if (!out) throw Error("cannot write " + path + ": write failed (disk full?)");
}

}  // namespace cenote::eval
