#include "io/bag/ros_image.h"

#include <bit>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string_view>

#include "common/error.h"
#include "io/image/image_header.h"
#include "io/image/opencv_codecs.h"
#include "io/image/png_decoder.h"

namespace cenote::io {
namespace {

// One sensor_msgs/Image encoding (ROS's names, sensor_msgs/image_encodings.h): how its bytes are
// laid out and which cv::cvtColor code makes them grey or BGR.
struct RosEncoding {
  std::string_view name;
  int channels;        // samples a pixel as stored (YUV 4:2:2: two bytes a pixel)
  int depth;           // CV_8U or CV_16U
  int to_bgr = -1;     // cv::cvtColor code after the samples are 8-bit; -1: already grey or BGR
  bool pairs = false;  // YUV 4:2:2: two neighbouring pixels share U and V, so the width is even
};

// A Bayer pattern is named by the colours of its first row and then its second (rggb: R G, G B);
// OpenCV 4 names its codes the same way (COLOR_BayerRGGB2BGR). YUV 4:2:2: "yuv422" is UYVY and
// "yuv422_yuy2" YUYV in ROS 1 and ROS 2 (ROS 2 also says "uyvy" and "yuyv").
constexpr RosEncoding kEncodings[] = {
    {"mono8", 1, CV_8U},
    {"8UC1", 1, CV_8U},
    {"mono16", 1, CV_16U},
    {"16UC1", 1, CV_16U},
    {"bgr8", 3, CV_8U},
    {"8UC3", 3, CV_8U},
    {"bgr16", 3, CV_16U},
    {"16UC3", 3, CV_16U},
    {"rgb8", 3, CV_8U, cv::COLOR_RGB2BGR},
    {"rgb16", 3, CV_16U, cv::COLOR_RGB2BGR},
    {"bgra8", 4, CV_8U, cv::COLOR_BGRA2BGR},
    {"8UC4", 4, CV_8U, cv::COLOR_BGRA2BGR},
    {"bgra16", 4, CV_16U, cv::COLOR_BGRA2BGR},
    {"16UC4", 4, CV_16U, cv::COLOR_BGRA2BGR},
    {"rgba8", 4, CV_8U, cv::COLOR_RGBA2BGR},
    {"rgba16", 4, CV_16U, cv::COLOR_RGBA2BGR},
    {"bayer_rggb8", 1, CV_8U, cv::COLOR_BayerRGGB2BGR},
    {"bayer_bggr8", 1, CV_8U, cv::COLOR_BayerBGGR2BGR},
    {"bayer_gbrg8", 1, CV_8U, cv::COLOR_BayerGBRG2BGR},
    {"bayer_grbg8", 1, CV_8U, cv::COLOR_BayerGRBG2BGR},
    {"bayer_rggb16", 1, CV_16U, cv::COLOR_BayerRGGB2BGR},
    {"bayer_bggr16", 1, CV_16U, cv::COLOR_BayerBGGR2BGR},
    {"bayer_gbrg16", 1, CV_16U, cv::COLOR_BayerGBRG2BGR},
    {"bayer_grbg16", 1, CV_16U, cv::COLOR_BayerGRBG2BGR},
    {"yuv422", 2, CV_8U, cv::COLOR_YUV2BGR_UYVY, true},
    {"uyvy", 2, CV_8U, cv::COLOR_YUV2BGR_UYVY, true},
    {"yuv422_yuy2", 2, CV_8U, cv::COLOR_YUV2BGR_YUYV, true},
    {"yuyv", 2, CV_8U, cv::COLOR_YUV2BGR_YUYV, true},
};

constexpr const char* kEncodingsRead =
    "cenote reads mono8/16, bgr8/16, rgb8/16, bgra8/16, rgba8/16, bayer_{rggb,bggr,gbrg,grbg}8/16, yuv422 (uyvy) "
    "and yuv422_yuy2 (yuyv)";

const RosEncoding* findEncoding(std::string_view name) {
  for (const RosEncoding& e : kEncodings) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

// 16-bit samples holding `bits` significant bits as 8-bit, full scale to full scale
// (x 255 / (2^bits - 1), rounded; larger values saturate), after putting them in this machine's
// byte order (the message says which order it was written in).
cv::Mat eightBitSamples(const cv::Mat& samples16, bool big_endian, int bits = 16) {
  cv::Mat host = samples16;
  if (big_endian != (std::endian::native == std::endian::big)) {
    host = samples16.clone();
    for (int y = 0; y < host.rows; ++y) {
      auto* row = host.ptr<std::uint16_t>(y);
      for (int i = 0; i < host.cols * host.channels(); ++i) row[i] = static_cast<std::uint16_t>(row[i] >> 8 | row[i] << 8);
    }
  }
  cv::Mat out;
  host.convertTo(out, CV_8U, 255.0 / ((1 << bits) - 1));
  return out;
}

}  // namespace

cv::Mat imageToMat(const RosImage& image, const std::string& topic, int sample_bits) {
  const std::string& enc = image.encoding;
  const RosEncoding* encoding = findEncoding(enc);
  if (encoding == nullptr) throw Error("topic " + topic + ": image encoding " + enc + " is not read; " + kEncodingsRead);
  if (image.width == 0 || image.height == 0) throw Error("topic " + topic + ": empty image (" + enc + ")");
  if (encoding->pairs && image.width % 2 != 0) {
    throw Error("topic " + topic + ": image encoding " + enc + " needs an even width (two pixels share U and V), got " +
                std::to_string(image.width));
  }
  const std::size_t sample_bytes = encoding->depth == CV_16U ? 2 : 1;
  const std::size_t row_bytes = static_cast<std::size_t>(image.width) * encoding->channels * sample_bytes;
  if (image.step < row_bytes) {
    throw Error("topic " + topic + ": image step " + std::to_string(image.step) + " is less than width " +
                std::to_string(image.width) + " x " + std::to_string(encoding->channels * sample_bytes) + " bytes");
  }
  if (image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    throw Error("topic " + topic + ": image data holds " + std::to_string(image.data.size()) + " bytes, " +
                std::to_string(image.height) + " rows of step " + std::to_string(image.step) + " need " +
                std::to_string(static_cast<std::size_t>(image.step) * image.height));
  }
  const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width),
                     CV_MAKETYPE(encoding->depth, encoding->channels), const_cast<std::uint8_t*>(image.data.data()),
                     image.step);
  // The Mat returned owns its pixels: the message's bytes belong to the recording's buffer.
  const cv::Mat samples = encoding->depth == CV_16U ? eightBitSamples(view, image.is_bigendian != 0, sample_bits) : view;
  if (encoding->to_bgr < 0) return samples.data == view.data ? view.clone() : samples;
  cv::Mat out;
  cv::cvtColor(samples, out, encoding->to_bgr);
  return out;
}

cv::Mat compressedImageToMat(const RosCompressedImage& image, const std::string& topic) {
  const auto& d = image.data;
  const bool png = d.size() >= 8 && std::memcmp(d.data(), "\x89PNG\r\n\x1a\n", 8) == 0;
  const bool jpeg = d.size() >= 3 && d[0] == 0xFF && d[1] == 0xD8 && d[2] == 0xFF;
  const std::string where = "topic " + topic + ": compressed image (format '" + image.format + "', " +
                            std::to_string(d.size()) + " bytes)";
  if (!png && !jpeg) throw Error(where + " is neither JPEG nor PNG");
  // The header and the data's bound first (image_header.h): a decoder allocates the pixels a header
  // claims before it reads the data, and a few KB that claim 30000x30000 would cost it 900 MB.
  if (png) {
    checkPngStructure(d.data(), d.size(), where);
  } else if (const ImageHeader header = readImageHeader(d.data(), d.size(), where); !header.dataCanHold()) {
    throw Error(where + ": JPEG claims " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                " pixels, more than its " + std::to_string(header.data_bytes) + " bytes of data can hold");
  }
  cv::Mat out;
  if (png) out = decodePngFast(d.data(), d.size(), ChunkCrc::kAlreadyChecked);
  if (out.empty()) {
    try {
      out = opencvDecode(d.data(), d.size(), cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {  // OpenCV's decoders throw on some damaged data
      throw Error(where + " cannot be decoded: " + e.err);
    }
  }
  if (out.empty()) throw Error(where + " cannot be decoded");
  // A 16-bit PNG: decoded in this machine's byte order.
  if (out.depth() == CV_16U) out = eightBitSamples(out, std::endian::native == std::endian::big);
  if (out.depth() != CV_8U) throw Error(where + " is neither 8 nor 16 bits a sample");
  if (out.channels() == 4) cv::cvtColor(out, out, cv::COLOR_BGRA2BGR);
  return out;
}

}  // namespace cenote::io
