// frame_decoder.h: a wire stereo frame (proto/cenote/v1/ingest.proto) into the pipeline's raw
// pair: PNG / JPEG through OpenCV's imdecode (unchanged depth and channels, as the dataset readers
// load files, so a frame sent over gRPC matches the same file read by `cenote run`), or raw
// pixels with an explicit encoding. Every failure names the image and what is wrong with it.
// Threads: pure functions.
#pragma once

#include "cenote/v1/ingest.pb.h"
#include "pipeline/frame/frames.h"

namespace cenote::server {

// @throws StatusError INVALID_ARGUMENT for undecodable data, a raw buffer whose size does not match
//   width x height x channels, an unspecified encoding or an empty image; RESOURCE_EXHAUSTED for an
//   image of more than max_pixels.
pipeline::StereoFrame decodeStereoFrame(const v1::StereoFrame& frame, int64_t max_pixels);

}  // namespace cenote::server
