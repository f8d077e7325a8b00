// zstd_stream.h: zstd decompression of what rosbag2's compression writes (compression_format zstd):
// one message's bytes (compression_mode MESSAGE) and a whole .db3 file (compression_mode FILE).
// Both read the data as a stream of frames, so a frame with or without its content size decodes
// (rosbag2's ZSTD_compress stores it; a streaming compressor need not), in bounded memory for files.
// Errors: IoError with zstd's own reason ("zstd: Unknown frame descriptor"), for a message also when
// it would decompress to more than `max_bytes`; for a file naming the file.
// Threads: free functions; TempFile is one object per file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace cenote::io {

/// Decompresses `in` (one or more zstd frames) into `out` (resized to the decompressed bytes). `out` grows
/// with what decodes: a frame's declared content size is allocated up front only when its bytes could
/// plausibly hold it.
/// @throws IoError "zstd: <reason>" for data that is not zstd, is cut short or exceeds `max_bytes`.
void zstdDecompress(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out,
                    std::size_t max_bytes = std::size_t{1} << 30);

/// Decompresses the zstd file `src` into `dst` (created or truncated), a buffer at a time.
/// @throws IoError naming `src` for what zstd rejects or a stream cut short; NotFoundError when `src`
///         does not exist; ResourceExhaustedError / IoError naming `dst` when it cannot be written.
void zstdDecompressFile(const std::filesystem::path& src, const std::filesystem::path& dst);

/// A file of its own in the temporary folder (TMPDIR, else /tmp), removed when the object goes.
class TempFile {
 public:
  /// @param name_hint a part of the file's name ("dive_0.db3": cenote-dive_0.db3-Ab12Cd).
  /// @throws IoError naming the folder when no file can be created there.
  explicit TempFile(const std::string& name_hint);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace cenote::io
