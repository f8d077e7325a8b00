#include "io/image/jpeg_decoder.h"

// clang-format off
#include <cstdio>  // jpeglib.h needs FILE and size_t first
#include <jpeglib.h>
// clang-format on

#include <csetjmp>

#include "common/error.h"

namespace cenote::io {
namespace {

// libjpeg reports through these callbacks; every one ends the decode by a longjmp back into
// decodeInto() with the message kept (libjpeg is C: no exception may cross it).
struct Reporter {
  jpeg_error_mgr manager;  // first: libjpeg hands back a pointer to it
  jpeg_progress_mgr progress;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = {};
};

[[noreturn]] void onError(j_common_ptr cinfo) {
  auto* r = reinterpret_cast<Reporter*>(cinfo->err);
  cinfo->err->format_message(cinfo, r->message);
  std::longjmp(r->jump, 1);
}

// msg_level -1 is a warning (corrupt or missing data that libjpeg would paper over); 0 and above
// are trace messages.
void onMessage(j_common_ptr cinfo, int msg_level) {
  if (msg_level < 0) onError(cinfo);
}

void onProgress(j_common_ptr cinfo) {
  auto* d = reinterpret_cast<j_decompress_ptr>(cinfo);
  if (d->input_scan_number > kMaxJpegScans) {
    auto* r = reinterpret_cast<Reporter*>(cinfo->err);
    std::snprintf(r->message, sizeof(r->message), "more than %d scans", kMaxJpegScans);
    std::longjmp(r->jump, 1);
  }
}

enum class Outcome { kDecoded, kFailed, kTooLarge };

// The decode proper, with no C++ object alive across the setjmp that needs its destructor (the
// image is the caller's). The reason for a failure is left in reporter.message.
Outcome decodeInto(jpeg_decompress_struct& cinfo, Reporter& reporter, const uint8_t* data, std::size_t size,
                   uint64_t max_pixels, cv::Mat& image) {
  cinfo.err = jpeg_std_error(&reporter.manager);
  reporter.manager.error_exit = onError;
  reporter.manager.emit_message = onMessage;
  reporter.progress.progress_monitor = onProgress;
  if (setjmp(reporter.jump) != 0) return Outcome::kFailed;
  jpeg_create_decompress(&cinfo);
  cinfo.progress = &reporter.progress;
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  if (cinfo.num_components != 1 && cinfo.num_components != 3) {
    std::snprintf(reporter.message, sizeof(reporter.message), "%d components (CMYK?): only grey and colour are taken",
                  cinfo.num_components);
    return Outcome::kFailed;
  }
  if (uint64_t{cinfo.image_width} * cinfo.image_height > max_pixels) {
    std::snprintf(reporter.message, sizeof(reporter.message), "%ux%u: more than %llu pixels", cinfo.image_width,
                  cinfo.image_height, static_cast<unsigned long long>(max_pixels));
    return Outcome::kTooLarge;
  }
  // As OpenCV's decoder (grfmt_jpeg.cpp): BGR straight from libjpeg-turbo, grey as grey.
  const bool colour = cinfo.num_components == 3;
  cinfo.out_color_space = colour ? JCS_EXT_BGR : JCS_GRAYSCALE;
  cinfo.out_color_components = colour ? 3 : 1;
  jpeg_start_decompress(&cinfo);
  image.create(static_cast<int>(cinfo.output_height), static_cast<int>(cinfo.output_width), colour ? CV_8UC3 : CV_8UC1);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = image.ptr<uint8_t>(static_cast<int>(cinfo.output_scanline));
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  return Outcome::kDecoded;
}

}  // namespace

cv::Mat decodeJpegStrict(const uint8_t* data, std::size_t size, const std::string& what, uint64_t max_pixels) {
  jpeg_decompress_struct cinfo{};
  Reporter reporter;
  cv::Mat image;
  const Outcome outcome = decodeInto(cinfo, reporter, data, size, max_pixels, image);
  jpeg_destroy_decompress(&cinfo);
  if (outcome == Outcome::kTooLarge) throw ResourceExhaustedError(what + ": JPEG of " + std::string(reporter.message));
  if (outcome == Outcome::kFailed) throw Error(what + ": JPEG cannot be decoded: " + std::string(reporter.message));
  return image;
}

}  // namespace cenote::io
