#include "io/bag/zstd_stream.h"

#include <unistd.h>
#include <zstd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "common/error.h"
#include "io/bag/output_growth.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

struct DStreamFree {
  void operator()(ZSTD_DStream* s) const { ZSTD_freeDStream(s); }
};
using DStream = std::unique_ptr<ZSTD_DStream, DStreamFree>;

// A frame's declared content size becomes the output's size in one call only up to kPresizeRatio times
// the frame's bytes (output_growth.h: a declared size is as damaged as the rest can be). A frame that
// compresses further (all-zero images) is decompressed as a stream, its output growing with what decodes.
using detail::kPresizeRatio;

DStream newStream() {
  DStream s(ZSTD_createDStream());
  if (!s) throw IoError("zstd: out of memory");
  ZSTD_initDStream(s.get());
  return s;
}

// Feeds `in` through `stream`, handing each decompressed piece to `sink`. @return ZSTD's hint: 0 when
// the last frame is complete.
template <class Sink>
std::size_t feed(ZSTD_DStream* stream, ZSTD_inBuffer& in, std::vector<std::uint8_t>& buffer, Sink&& sink) {
  std::size_t hint = 1;
  while (in.pos < in.size) {
    ZSTD_outBuffer out{buffer.data(), buffer.size(), 0};
    hint = ZSTD_decompressStream(stream, &out, &in);
    if (ZSTD_isError(hint)) throw IoError(std::string("zstd: ") + ZSTD_getErrorName(hint));
    sink(buffer.data(), out.pos);
  }
  // Output zstd holds back once the input is used up (a full buffer leaves some behind).
  while (hint != 0) {
    ZSTD_outBuffer out{buffer.data(), buffer.size(), 0};
    hint = ZSTD_decompressStream(stream, &out, &in);
    if (ZSTD_isError(hint)) throw IoError(std::string("zstd: ") + ZSTD_getErrorName(hint));
    sink(buffer.data(), out.pos);
    if (out.pos < out.size) break;  // nothing held back: the frame wants more input
  }
  return hint;
}

struct FileClose {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileClose>;

}  // namespace

void zstdDecompress(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out, std::size_t max_bytes) {
  out.clear();
  const unsigned long long declared = ZSTD_getFrameContentSize(in.data(), in.size());
  if (declared == ZSTD_CONTENTSIZE_ERROR) throw IoError("zstd: not a zstd frame");
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared <= max_bytes && declared <= kPresizeRatio * in.size()) {
    // One call where the frame says its size (rosbag2's messages do) and its bytes could hold it: no
    // stream, buffer or copies.
    out.resize(static_cast<std::size_t>(declared));
    const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
    if (!ZSTD_isError(n) && n == out.size()) return;
    out.clear();  // damaged, cut, or more than one frame: the stream below says which
    out.reserve(static_cast<std::size_t>(declared));
  }
  const DStream stream = newStream();
  std::vector<std::uint8_t> buffer(ZSTD_DStreamOutSize());
  ZSTD_inBuffer src{in.data(), in.size(), 0};
  const std::size_t hint = feed(stream.get(), src, buffer, [&](const std::uint8_t* p, std::size_t n) {
    if (out.size() + n > max_bytes) {
      throw IoError("zstd: decompresses to more than the " + std::to_string(max_bytes) + " bytes this reader holds");
    }
    out.insert(out.end(), p, p + n);
  });
  if (hint != 0) throw IoError("zstd: the data end inside a frame (cut short)");
}

void zstdDecompressFile(const fs::path& src, const fs::path& dst) {
  const File in(std::fopen(src.c_str(), "rb"));
  if (!in) throwReadError(src.string(), std::strerror(errno));
  const File out(std::fopen(dst.c_str(), "wb"));
  if (!out) throwWriteError(dst.string(), std::strerror(errno), errno);
  const DStream stream = newStream();
  std::vector<std::uint8_t> input(ZSTD_DStreamInSize()), buffer(ZSTD_DStreamOutSize());
  std::size_t hint = 1;
  try {
    while (true) {
      const std::size_t n = std::fread(input.data(), 1, input.size(), in.get());
      if (n == 0) break;
      ZSTD_inBuffer chunk{input.data(), n, 0};
      hint = feed(stream.get(), chunk, buffer, [&](const std::uint8_t* p, std::size_t size) {
        if (size > 0 && std::fwrite(p, 1, size, out.get()) != size)
          throwWriteError(dst.string(), std::strerror(errno), errno);
      });
    }
  } catch (const IoError& e) {
    if (std::string(e.what()).rfind("zstd: ", 0) == 0) throw IoError(src.string() + ": " + e.what());
    throw;
  }
  if (std::ferror(in.get())) throw IoError("cannot read " + src.string() + ": " + std::strerror(errno));
  if (hint != 0) throw IoError(src.string() + ": zstd: the file ends inside a frame (cut short)");
  if (std::fflush(out.get()) != 0) throwWriteError(dst.string(), std::strerror(errno), errno);
}

TempFile::TempFile(const std::string& name_hint) {
  std::error_code ec;
  const fs::path folder = fs::temp_directory_path(ec);
  if (ec) throw IoError("no temporary folder for the decompressed copy of " + name_hint + ": " + ec.message());
  std::string pattern = (folder / ("cenote-" + name_hint + "-XXXXXX")).string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0) {
    throw IoError("cannot create a temporary file in " + folder.string() + " for the decompressed copy of " + name_hint +
                  ": " + std::strerror(errno) + " (set TMPDIR to a writable folder)");
  }
  ::close(fd);
  path_ = pattern;
}

TempFile::~TempFile() {
  std::error_code ec;
  fs::remove(path_, ec);
}

}  // namespace cenote::io
