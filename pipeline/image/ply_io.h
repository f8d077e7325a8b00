// ply_io.h: coloured point clouds as binary little-endian PLY files.
// Layout written (and the only one read): vertex x y z float32, red green blue uint8
// (15 bytes per point), no faces. Units and frame: whatever the points are in (cenote writes world
// metres). Colours: RGB.
// Writes go to a temporary file renamed into place at the end, so a crash never leaves half a file.
// Threads: a PlyWriter belongs to one thread; the free functions are independent.
#pragma once

#include <array>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "common/point_batch.h"

namespace cenote::pipeline {

struct PlyPoints {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<uint8_t, 3>> colors;  // RGB, one per point
};

// Streams batches into one PLY file without keeping the points in memory: the vertex count is
// written into a fixed-size header when the writer is closed.
class PlyWriter {
 public:
  // Creates `path`.tmp. @throws cenote::Error when it cannot be created.
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
  std::string path_;
  std::ofstream out_;
  size_t count_ = 0;
  bool closed_ = false;
  std::vector<char> buffer_;
};

// One-shot write. @throws cenote::Error when points and colors differ in size (colors may be
// empty: grey) or the file cannot be written.
void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors);

// Reads a file of the layout above. @throws cenote::Error when missing, truncated, or of another
// format or layout (naming what was found).
PlyPoints readPly(const std::string& path);

}  // namespace cenote::pipeline
