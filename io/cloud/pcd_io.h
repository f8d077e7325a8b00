// pcd_io.h: point clouds as PCD files (PCL's format, v0.7), read and written by PCL's own code
// (pcl::PCDReader, pcl::PCDWriter), so that what robotics tools write we read, and what we write
// they read. No PCL type appears here: PCL's headers are seen by pcd_io.cpp alone.
// Written layout: fields x y z (float32) and, for a coloured cloud, rgb (PCL's packed float,
// 0x00RRGGBB), WIDTH = POINTS = n, HEIGHT 1, DATA binary unless asked otherwise.
// Read: DATA ascii, binary or binary_compressed; x, y, z of any PCD type (F 4/8, I or U of 1, 2, 4
// bytes); colours from a field rgb (F or U, 4 bytes) or rgba (U 4); any other field is skipped.
// Units and frame: whatever the points are in (cenote writes world metres).
// Writes go to a temporary file renamed into place at the end: a crash never leaves half a file.
// Threads: free functions, independent.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace cenote::io {

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };

struct PcdPoints {
  std::vector<Eigen::Vector3f> points;         // finite points only
  std::vector<std::array<uint8_t, 3>> colors;  // RGB, one per point; empty when the file has no rgb/rgba
  size_t non_finite_dropped = 0;               // points with a NaN or infinite coordinate (PCL's "missing")
};

// Writes `points` (and `colors`, one per point, or none: then fields x y z only). An empty cloud
// gives a valid file of 0 points.
// @throws cenote::Error when points and colors differ in size, or the file cannot be written
//         (naming the path and PCL's reason).
void writePcd(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors, PcdEncoding encoding = PcdEncoding::kBinary);

// @throws cenote::Error naming the file when it is missing, not a PCD file PCL reads, or has no x/y/z.
PcdPoints readPcd(const std::string& path);

}  // namespace cenote::io
