// read_rectify_bench: CPU ms per 800x600 colour PNG of the read+rectify stage of `cenote run`,
// split into its parts, with cenote's PNG decoder (ISA-L's igzip, io/image/png_decoder.h) beside
// libspng and OpenCV's libpng decoder on the same files in the same run, and the inflating alone
// (most of a PNG's decoding) by igzip, libdeflate and zlib on the same IDAT streams.
//   read_rectify_bench --dataset DIR [--frames 20]
// DIR is a EuRoC folder (`cenote sim --scene cave --out DIR`). CPU time is the thread's own
// (CLOCK_THREAD_CPUTIME_ID), single-threaded, best of 3 passes over the frames. Every decoder's
// pixels are compared with ours; a difference is an error (exit 1).
#include <CLI/CLI.hpp>
#include <isa-l/igzip_lib.h>
#include <libdeflate.h>
#include <spng.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "common/cpu_clock.h"
#include "io/image/png_decoder.h"
#include "pipeline/calibration/rectifier.h"
#include "pipeline/dataset/euroc_dataset.h"

using namespace cenote;

namespace {

std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

// libspng to 8-bit RGB, then to OpenCV's BGR order (what the pipeline takes); empty on failure.
cv::Mat decodeSpng(const std::vector<uint8_t>& bytes) {
  spng_ctx* ctx = spng_ctx_new(0);
  cv::Mat out;
  spng_ihdr ihdr{};
  size_t size = 0;
  if (spng_set_png_buffer(ctx, bytes.data(), bytes.size()) == 0 && spng_get_ihdr(ctx, &ihdr) == 0 &&
      spng_decoded_image_size(ctx, SPNG_FMT_RGB8, &size) == 0) {
    out.create(static_cast<int>(ihdr.height), static_cast<int>(ihdr.width), CV_8UC3);
    if (spng_decode_image(ctx, out.data, size, SPNG_FMT_RGB8, 0) == 0) {
      cv::cvtColor(out, out, cv::COLOR_RGB2BGR);
    } else {
      out.release();
    }
  }
  spng_ctx_free(ctx);
  return out;
}

// The three inflaters on one zlib stream into `out` (its exact size); false on failure.
bool inflateIgzip(std::span<const uint8_t> in, std::vector<uint8_t>& out) {
  static inflate_state state;
  isal_inflate_init(&state);
  state.crc_flag = ISAL_ZLIB;
  state.next_in = const_cast<uint8_t*>(in.data());
  state.avail_in = static_cast<uint32_t>(in.size());
  state.next_out = out.data();
  state.avail_out = static_cast<uint32_t>(out.size());
  return isal_inflate_stateless(&state) == ISAL_DECOMP_OK && state.avail_out == 0;
}

bool inflateLibdeflate(std::span<const uint8_t> in, std::vector<uint8_t>& out) {
  static libdeflate_decompressor* const d = libdeflate_alloc_decompressor();
  return libdeflate_zlib_decompress(d, in.data(), in.size(), out.data(), out.size(), nullptr) == LIBDEFLATE_SUCCESS;
}

bool inflateZlib(std::span<const uint8_t> in, std::vector<uint8_t>& out) {
  uLongf size = out.size();
  return uncompress(out.data(), &size, in.data(), in.size()) == Z_OK && size == out.size();
}

// Best of three passes of `step` over every image, in CPU ms per image.
double cpuMsPerImage(size_t images, const std::function<void(size_t)>& step) {
  double best = 1e300;
  for (int pass = 0; pass < 3; ++pass) {
    const double t0 = threadCpuMs();
    for (size_t i = 0; i < images; ++i) step(i);
    best = std::min(best, (threadCpuMs() - t0) / static_cast<double>(images));
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("CPU of reading and rectifying PNG stereo frames, with libspng and libpng beside");
  std::string dataset_dir;
  int frames = 20;
  app.add_option("--dataset", dataset_dir, "EuRoC folder (cenote sim --out)")->required();
  app.add_option("--frames", frames, "Frames to read")->check(CLI::Range(1, 10000));
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);  // one thread's CPU, as the reader's own share

  const pipeline::EurocDataset dataset(dataset_dir);
  const pipeline::Rectifier rectifier(dataset.calibration());
  // Left and right images of the first frames, in pairs (EuRoC names its images by timestamp).
  std::vector<std::vector<std::string>> paths(2);
  for (int cam = 0; cam < 2; ++cam) {
    const std::filesystem::path folder = std::filesystem::path(dataset_dir) / "mav0" / ("cam" + std::to_string(cam)) /
                                         "data";
    for (const auto& e : std::filesystem::directory_iterator(folder)) paths[cam].push_back(e.path().string());
    std::sort(paths[cam].begin(), paths[cam].end());
  }
  std::vector<std::vector<uint8_t>> files;
  for (size_t f = 0; f < std::min({paths[0].size(), paths[1].size(), static_cast<size_t>(frames)}); ++f) {
    for (int cam = 0; cam < 2; ++cam) files.push_back(readBytes(paths[cam][f]));
  }
  if (files.empty()) {
    std::fprintf(stderr, "read_rectify_bench: no images in %s/mav0/cam0/data\n", dataset_dir.c_str());
    return 1;
  }
  const size_t n = files.size();
  std::vector<cv::Mat> ours(n);
  for (size_t i = 0; i < n; ++i) ours[i] = io::decodePngFast(files[i].data(), files[i].size());
  for (size_t i = 0; i < n; ++i) {
    const cv::Mat spng = decodeSpng(files[i]);
    const cv::Mat libpng = cv::imdecode(files[i], cv::IMREAD_UNCHANGED);
    if (ours[i].empty() || spng.size() != ours[i].size() || libpng.size() != ours[i].size() ||
        cv::norm(spng, ours[i], cv::NORM_INF) != 0 || cv::norm(libpng, ours[i], cv::NORM_INF) != 0) {
      std::fprintf(stderr, "read_rectify_bench: image %zu: the decoders' pixels differ\n", i);
      return 1;
    }
  }
  std::vector<io::PngImageData> streams(n);
  for (size_t i = 0; i < n; ++i) {
    if (!io::readPngImageData(files[i].data(), files[i].size(), streams[i])) {
      std::fprintf(stderr, "read_rectify_bench: image %zu: no image data to inflate\n", i);
      return 1;
    }
  }
  std::vector<uint8_t> raw(static_cast<size_t>(streams[0].width * streams[0].channels + 1) * streams[0].height);
  std::vector<uint8_t> raw_check(raw.size());
  for (size_t i = 0; i < n; ++i) {
    const bool ok = inflateIgzip(streams[i].zlib, raw) && inflateLibdeflate(streams[i].zlib, raw_check) &&
                    raw == raw_check && inflateZlib(streams[i].zlib, raw_check) && raw == raw_check;
    if (!ok) {
      std::fprintf(stderr, "read_rectify_bench: image %zu: the inflaters' bytes differ\n", i);
      return 1;
    }
  }
  const double ours_ms = cpuMsPerImage(n, [&](size_t i) { io::decodePngFast(files[i].data(), files[i].size()); });
  const double spng_ms = cpuMsPerImage(n, [&](size_t i) { decodeSpng(files[i]); });
  const double libpng_ms = cpuMsPerImage(n, [&](size_t i) { cv::imdecode(files[i], cv::IMREAD_UNCHANGED); });
  const double igzip_ms = cpuMsPerImage(n, [&](size_t i) { inflateIgzip(streams[i].zlib, raw); });
  const double libdeflate_ms = cpuMsPerImage(n, [&](size_t i) { inflateLibdeflate(streams[i].zlib, raw); });
  const double zlib_ms = cpuMsPerImage(n, [&](size_t i) { inflateZlib(streams[i].zlib, raw); });
  const double rectify_ms = cpuMsPerImage(n / 2,
                                          [&](size_t f) {
                                            rectifier.rectify(pipeline::StereoFrame{0.0, ours[2 * f], ours[2 * f + 1]});
                                          }) /
                            2.0;
  std::printf("%zu images of %dx%d, %zu KiB each on average; CPU ms per image (one thread):\n", n, ours[0].cols,
              ours[0].rows, [&] {
                size_t total = 0;
                for (const auto& f : files) total += f.size();
                return total / n / 1024;
              }());
  std::printf("| decode: cenote (igzip) | libspng %d.%d.%d | OpenCV (libpng) | libspng / ours | libpng / ours | "
              "rectify (%s) |\n",
              SPNG_VERSION_MAJOR, SPNG_VERSION_MINOR, SPNG_VERSION_PATCH,
              rectifier.keepsImages() ? "identity maps: images handed on" : "cv::remap, CV_16SC2 maps");
  std::printf("|---|---|---|---|---|---|\n");
  std::printf("| %.2f | %.2f | %.2f | %.2fx | %.2fx | %.2f |\n", ours_ms, spng_ms, libpng_ms, spng_ms / ours_ms,
              libpng_ms / ours_ms, rectify_ms);
  std::printf("\nInflating alone, the same IDAT streams, CPU ms per image:\n");
  std::printf("| igzip (ours) | libdeflate | zlib | libdeflate / igzip | zlib / igzip |\n|---|---|---|---|---|\n");
  std::printf("| %.2f | %.2f | %.2f | %.2fx | %.2fx |\n", igzip_ms, libdeflate_ms, zlib_ms, libdeflate_ms / igzip_ms,
              zlib_ms / igzip_ms);
  return 0;
}
