// depth_folder.h: the depth maps of a folder, keyed by image name, in any of the formats the
// evaluation reads, loaded as float metres.
//   <name>.pfm, <name>.depth.pfm         float32 (Middlebury PFM), metres; +inf/NaN/<= 0 = none
//   <name>.png, <name>.depth.png         16-bit PNG, millimetres (TUM convention); 0 = none
//   <image>.geometric.bin / .photometric.bin   COLMAP stereo/depth_maps; 0 = none
// The key is the file name without these suffixes and without an image extension left in it
// (COLMAP keeps the image's: "0012.png.geometric.bin" -> "0012"), so "0012.depth.pfm" of ours
// matches COLMAP's "0012.png.geometric.bin". Confidence maps (*.conf.pfm, *.conf.png) and
// previews (*.preview.png) are skipped. When several files give one key, PFM wins over PNG, and
// the preferred COLMAP kind over the other.
// A COLMAP workspace may be given instead of its depth_maps folder: DIR/stereo/depth_maps is used
// when DIR itself holds no depth map.
// Threads: free functions, independent.
#pragma once

#include <map>
#include <opencv2/core.hpp>
#include <string>

namespace cenote::eval {

enum class DepthFileKind { kPfm, kPng16, kColmapGeometric, kColmapPhotometric };

struct DepthFile {
  std::string path;
  DepthFileKind kind = DepthFileKind::kPfm;
};

// @param prefer_photometric choose *.photometric.bin over *.geometric.bin for one image.
// @return key -> file, sorted by key (empty when the folder holds no depth map).
// @throws cenote::Error when `dir` is not a directory.
std::map<std::string, DepthFile> listDepthMaps(const std::string& dir, bool prefer_photometric = false);

// The file's depth as CV_32FC1 metres with every invalid pixel (non-finite, <= 0) set to NaN.
// @throws cenote::Error naming the file when it is missing, malformed or not single-channel.
cv::Mat loadDepthMap(const DepthFile& file);

const char* toString(DepthFileKind kind);

}  // namespace cenote::eval
