// Fuzzes the image decoders on bytes held in memory, as wire frames and image files reach them:
// the header reader (io/image/image_header.h), the fast PNG decoder and the strict decoder of
// PNG and JPEG (io/image/image_io.h), with a pixel limit of 2^20.
#include <opencv2/core.hpp>

#include "common/error.h"
#include "io/image/image_header.h"
#include "io/image/image_io.h"
#include "io/image/png_decoder.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace cenote::io;
  static const uint8_t kEmpty = 0;
  if (data == nullptr) data = &kEmpty;
  cv::Mat fast = decodePngFast(data, size);  // never throws
  try {
    const ImageHeader header = readImageHeader(data, size, "fuzz");
    (void)header.dataCanHold();
  } catch (const cenote::Error&) {
  }
  try {
    cv::Mat image = decodeImageStrict(data, size, "fuzz", uint64_t{1} << 20);
    // What the strict decoder accepts, the fast one decodes the same way or leaves to OpenCV.
    if (!fast.empty() && (fast.size() != image.size() || fast.type() != image.type())) std::abort();
  } catch (const cenote::Error&) {
  }
  return 0;
}
