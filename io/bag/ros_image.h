// ros_image.h: the pixels of sensor_msgs/Image and sensor_msgs/CompressedImage as the 8-bit grey or
// BGR cv::Mat the pipeline takes.
//   Image: mono8 (grey), bgr8, rgb8 (to BGR), bgra8 / rgba8 (to BGR); mono16 and bayer_* are errors
//   that name the topic and the encoding (a mosaic needs debayering first: record image_mono or
//   image_color, or run image_proc).
//   CompressedImage: JPEG or PNG, told apart by the bytes' magic (FF D8 FF, 89 'PNG'), not by the
//   `format` string (drivers write "jpeg", "mono8; jpeg compressed bgr8", ...); anything else is an
//   error naming the topic and the format string.
// Threads: free functions; the Mat returned owns its pixels.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "io/bag/ros_messages.h"

namespace cenote::io {

/// @throws Error "topic /cam0/image_raw: image encoding bayer_rggb8 ..." for an encoding not read,
///         and for a step or data size that does not hold height rows of width pixels.
cv::Mat imageToMat(const RosImage& image, const std::string& topic);

/// @throws Error naming the topic and the format string when the bytes are neither JPEG nor PNG,
///         cannot be decoded, or are not 8-bit.
cv::Mat compressedImageToMat(const RosCompressedImage& image, const std::string& topic);

}  // namespace cenote::io
