// frame_decoder.h: a wire stereo frame (proto/cenote/v1/ingest.proto) into the pipeline's raw
// pair: PNG or JPEG (unchanged depth and channels, the pixels the dataset readers load from the
// same files, so a frame sent over gRPC matches the same file read by `cenote run`), or raw
// pixels with an explicit encoding. Everything that can be checked before decoding is: the
// format (PNG and JPEG only), the header's size against server.limits.max_image_pixels and the
// calibration, its bit depth and channels. Decoding is strict (io/image/image_io.h,
// decodeImageStrict): a truncated or corrupt image is refused, never padded. Every failure names
// the image and what is wrong with it.
// Threads: pure functions.
#pragma once

#include <opencv2/core.hpp>

#include "cenote/v1/ingest.pb.h"
#include "pipeline/frame/frames.h"

namespace cenote::server {

struct FrameLimits {
  int64_t max_pixels = 0;  // per image: server.limits.max_image_pixels
  cv::Size image_size;     // the calibrated size every image must have; empty: any size
};

// @throws StatusError INVALID_ARGUMENT for a format other than PNG / JPEG, a header that
//   disagrees with the calibration, a bit depth other than 8, 2 channels (grey + alpha), truncated
//   or corrupt data, a raw buffer whose size does not match width x height x channels, an
//   unspecified encoding, an empty image, or left and right of different sizes;
//   RESOURCE_EXHAUSTED for an image of more than limits.max_pixels (before it is decoded).
pipeline::StereoFrame decodeStereoFrame(const v1::StereoFrame& frame, const FrameLimits& limits);

}  // namespace cenote::server
