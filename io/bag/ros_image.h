// ros_image.h: the pixels of sensor_msgs/Image and sensor_msgs/CompressedImage as the 8-bit grey or
// BGR cv::Mat the pipeline takes.
//   Image: mono8 / mono16 (grey); bgr8/16, rgb8/16, bgra8/16, rgba8/16 (to BGR); Bayer mosaics
//   bayer_{rggb,bggr,gbrg,grbg}8/16, demosaiced to BGR (OpenCV's bilinear demosaicing); YUV 4:2:2,
//   yuv422 (UYVY) and yuv422_yuy2 (YUYV), to BGR (BT.601). 16-bit samples become 8-bit full scale
//   to full scale (x 255 / 65535, rounded) in the byte order the message gives (is_bigendian), or
//   with `sample_bits` < 16 from that many low bits (a 12-bit camera writing 0..4095 into mono16).
//   Any other encoding is an error that names the topic, the encoding and the ones read.
//   CompressedImage: JPEG or PNG, told apart by the bytes' magic (FF D8 FF, 89 'PNG'), not by the
//   `format` string (drivers write "jpeg", "mono8; jpeg compressed bgr8", ...); anything else is an
//   error naming the topic and the format string. A 16-bit PNG becomes 8-bit as above.
// Threads: free functions; the Mat returned owns its pixels.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "io/bag/ros_messages.h"

namespace cenote::io {

/// @throws Error "topic /cam0/image_raw: image encoding 32FC1 is not read; ..." for an encoding not
///         read, for a step or data size that does not hold height rows of width pixels, and for
///         YUV 4:2:2 of an odd width.
/// `sample_bits`: the significant low bits of 16-bit samples, in [9, 16] (the caller's check).
cv::Mat imageToMat(const RosImage& image, const std::string& topic, int sample_bits = 16);

/// @throws Error naming the topic and the format string when the bytes are neither JPEG nor PNG, claim
///         more pixels than their data can hold (io/image/image_header.h: checked before decoding),
///         cannot be decoded, or are neither 8 nor 16 bits a sample.
cv::Mat compressedImageToMat(const RosCompressedImage& image, const std::string& topic);

}  // namespace cenote::io
