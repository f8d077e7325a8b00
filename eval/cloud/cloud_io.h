// cloud_io.h: point clouds for evaluation, read from PLY or PCD files of any common layout.
//   PLY: ascii, binary_little_endian or binary_big_endian; a "vertex" element with x, y, z of any
//        scalar type (other properties, list properties and other elements are skipped).
//   PCD: read by PCL's own reader (io/cloud/pcd_io.h): DATA ascii, binary or
//        binary_compressed, fields x y z of type F (4 or 8 bytes), I or U, any other fields skipped.
// Only positions are read (metres in the file's frame). Points with a non-finite coordinate (PCD
// marks missing points with NaN) are dropped and counted.
// Threads: free functions, independent.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace cenote::eval {

struct Cloud {
  std::vector<Eigen::Vector3f> points;
  size_t non_finite_dropped = 0;
};

// By extension (.ply, .pcd; otherwise the first line decides).
// @throws cenote::Error naming the file when it is missing, of another format, has no x/y/z,
//         or is truncated or malformed (with the element or line at fault).
Cloud readCloud(const std::string& path);
Cloud readPlyCloud(const std::string& path);
Cloud readPcdCloud(const std::string& path);

// ASCII PCD writer (v0.7, fields x y z) written here by hand, independent of PCL: for tests and
// tools. @throws cenote::Error on write failure.
void writePcdAscii(const std::string& path, const std::vector<Eigen::Vector3f>& points);

}  // namespace cenote::eval
