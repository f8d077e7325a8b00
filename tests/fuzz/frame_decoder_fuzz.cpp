// Fuzzes what the frame handler does with a frame before the pipeline (server/services/
// ingest_service.cpp): the input is a serialized v1::StereoFrame, as Ingest.StreamFrames receives
// it; its own pose is checked (server/wire/wire.h finitePose) and its images decoded
// (server/wire/frame_decoder.h) against a 64x48 calibration and a limit of 2^20 pixels. Bad
// frames are refused with a StatusError.
#include "server/wire/frame_decoder.h"
#include "server/wire/status_error.h"
#include "server/wire/wire.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  cenote::v1::StereoFrame frame;
  if (!frame.ParseFromArray(data, static_cast<int>(size))) return 0;
  try {
    if (frame.has_pose()) (void)cenote::server::finitePose(frame.pose(), "pose");
  } catch (const cenote::server::StatusError&) {
  }
  try {
    const cenote::pipeline::StereoFrame raw = cenote::server::decodeStereoFrame(frame,
                                                                                {int64_t{1} << 20, cv::Size(64, 48)});
    if (raw.left.size() != cv::Size(64, 48) || raw.right.size() != cv::Size(64, 48)) std::abort();
  } catch (const cenote::server::StatusError&) {
  }
  return 0;
}
