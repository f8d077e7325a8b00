// colmap_depth_io.h: COLMAP's dense arrays (stereo/depth_maps/*.{geometric,photometric}.bin,
// normal maps), read and written natively.
// Layout (COLMAP src/mvs/mat.h, scripts/python/read_write_dense.py): an ASCII header
// "WIDTH&HEIGHT&CHANNELS&", then WIDTH*HEIGHT*CHANNELS little-endian float32 in Fortran order over
// (width, height, channels): element (x, y, c) at index x + WIDTH * (y + HEIGHT * c), i.e. one
// row-major plane per channel. Depth maps have one channel, metres (or the reconstruction's unit),
// 0 = no depth.
// Threads: free functions, independent.
#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace cenote::eval {

// @return CV_32FC1 (one channel) or CV_32FC(n), row-major, values as stored (0 stays 0).
// @throws cenote::Error naming the file when missing, when the header is not "W&H&C&" with
//         positive sizes, or when the data is shorter or longer than W*H*C floats.
cv::Mat readColmapArray(const std::string& path);

// Writes `array` (CV_32FC1..4) in COLMAP's layout. @throws cenote::Error when it cannot be written.
void writeColmapArray(const std::string& path, const cv::Mat& array);

}  // namespace cenote::eval
