// ply_io.h: coloured point clouds (and the map's meshes) as binary little-endian PLY files: the
// one PLY writer of cenote. It lives in the OpenCV-free target cenote_io_cloud (io/CMakeLists.txt),
// which cenote_mapping links for its exports (mapping/io/map_io.h) without linking OpenCV.
// Layout written (and the only one read): vertex x y z float32, red green blue uint8
// (15 bytes per point); writePlyMesh adds faces (list uchar int vertex_indices). Units and frame: whatever the points are in (cenote writes world
// metres). Colours: RGB.
// Writes go to a temporary file renamed into place at the end (common/atomic_file.h, durable: the
// file and its directory are fsynced), so a crash never leaves half a file.
// A PlyWriter streams: a batch is packed and written 240 KiB at a time (still in cache when the
// kernel copies it into the page cache), and every ~8 MB written is handed to the disk and dropped from the page cache
// once on disk, so a long run neither fills the cache nor pays for ever new cache pages (on this
// project's virtual machines, writing into fresh page cache cost ~4 ms of kernel time per MB,
// rewriting recycled pages a tenth of that).
// Threads: a PlyWriter belongs to one thread; the free functions are independent.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/point_batch.h"

namespace cenote::io {

struct PlyPoints {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<uint8_t, 3>> colors;  // RGB, one per point
};

// Streams batches into one PLY file without keeping the points in memory: the vertex count is
// written into a fixed-size header when the writer is closed.
class PlyWriter {
 public:
  // Creates temporaryPathFor(path). @throws cenote::Error (IoError) when it cannot be created.
  explicit PlyWriter(std::string path);
  // Removes the temporary file when close() was not called (e.g. after an error).
  ~PlyWriter();
  PlyWriter(const PlyWriter&) = delete;
  PlyWriter& operator=(const PlyWriter&) = delete;

  // Appends the batch's points; uncoloured batches are written grey (128, 128, 128).
  // @throws cenote::Error when the write fails.
  void append(const PointBatch& batch);
  // Writes the count, closes and renames into place. @throws cenote::Error when that fails.
  void close();

  size_t count() const { return count_; }

 private:
  void writeAll(const char* data, size_t size);
  // Starts writeback of what was written since the last call, then waits for the range before
  // it and drops it from the page cache.
  void writeBehind();

  std::string path_;
  std::string temp_path_;
  int fd_ = -1;
  size_t count_ = 0;
  bool closed_ = false;
  std::vector<char> buffer_;
  size_t written_bytes_ = 0;  // file size so far
  size_t flushed_bytes_ = 0;  // [0, flushed_bytes_) handed to the disk
  size_t dropped_bytes_ = 0;  // [0, dropped_bytes_) on disk and dropped from the cache
};

// One-shot write. @throws cenote::Error when points and colors differ in size (colors may be
// empty: grey) or the file cannot be written.
void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors);

// Vertices and triangles written at once, durably (mapping's points and mesh exports). The header
// is "ply", the format, "comment <comment>", the vertex element, and the face element when
// `triangles` is not empty. @throws cenote::Error when points and colors differ in size, or
// "cannot write <path>: <strerror>" (IoError; ResourceExhaustedError for a full disk).
void writePlyMesh(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                  const std::vector<std::array<uint8_t, 3>>& colors, const std::vector<std::array<uint32_t, 3>>& triangles,
                  const std::string& comment);

// Reads a file of the layout above. @throws cenote::Error when missing, truncated, or of another
// format or layout (naming what was found).
PlyPoints readPly(const std::string& path);

}  // namespace cenote::io
