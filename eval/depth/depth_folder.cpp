#include "eval/depth/depth_folder.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include "common/enum_names.h"
#include "common/error.h"
#include "eval/depth/colmap_depth_io.h"
#include "io/image/image_io.h"

namespace cenote::eval {
namespace {

namespace fs = std::filesystem;

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// Removes `suffix` (case-insensitive) when present; true when it was.
bool strip(std::string& name, const std::string& suffix) {
  if (!endsWith(lower(name), suffix) || name.size() == suffix.size()) return false;
  name.resize(name.size() - suffix.size());
  return true;
}

int rank(DepthFileKind kind, bool prefer_photometric) {
  switch (kind) {
    case DepthFileKind::kPfm: return 0;
    case DepthFileKind::kPng16: return 1;
    case DepthFileKind::kColmapGeometric: return prefer_photometric ? 3 : 2;
    case DepthFileKind::kColmapPhotometric: return prefer_photometric ? 2 : 3;
  }
  return 4;
}

std::map<std::string, DepthFile> listIn(const fs::path& dir, bool prefer_photometric) {
  std::map<std::string, DepthFile> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::string key = entry.path().filename().string();
    const std::string name = lower(key);
    if (endsWith(name, ".conf.pfm") || endsWith(name, ".conf.png") || endsWith(name, ".preview.png")) continue;
    DepthFile file;
    file.path = entry.path().string();
    if (strip(key, ".geometric.bin")) {
      file.kind = DepthFileKind::kColmapGeometric;
    } else if (strip(key, ".photometric.bin")) {
      file.kind = DepthFileKind::kColmapPhotometric;
    } else if (strip(key, ".pfm")) {
      file.kind = DepthFileKind::kPfm;
      strip(key, ".depth");
    } else if (strip(key, ".png")) {
      file.kind = DepthFileKind::kPng16;
      strip(key, ".depth");
    } else {
      continue;
    }
    for (const char* ext : {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".ppm", ".pgm"}) {
      if (strip(key, ext)) break;
    }
    const auto it = files.find(key);
    if (it == files.end() || rank(file.kind, prefer_photometric) < rank(it->second.kind, prefer_photometric)) {
      files[key] = file;
    }
  }
  return files;
}

}  // namespace

const char* toString(DepthFileKind kind) {
  constexpr EnumName<DepthFileKind> kNames[] = {{DepthFileKind::kPfm, "PFM"},
                                                {DepthFileKind::kPng16, "16-bit PNG"},
                                                {DepthFileKind::kColmapGeometric, "COLMAP geometric"},
                                                {DepthFileKind::kColmapPhotometric, "COLMAP photometric"}};
  return enumName(kNames, kind);
}

std::map<std::string, DepthFile> listDepthMaps(const std::string& dir, bool prefer_photometric) {
  if (!fs::is_directory(dir)) {
    throw Error(dir + ": " + (fs::exists(dir) ? "not a directory" : "no such directory"));
  }
  std::map<std::string, DepthFile> files = listIn(dir, prefer_photometric);
  const fs::path colmap = fs::path(dir) / "stereo" / "depth_maps";
  if (files.empty() && fs::is_directory(colmap)) files = listIn(colmap, prefer_photometric);
  return files;
}

cv::Mat loadDepthMap(const DepthFile& file) {
  cv::Mat depth;
  switch (file.kind) {
    case DepthFileKind::kPfm: depth = io::readPfm(file.path); break;
    case DepthFileKind::kPng16: depth = io::readDepthPng16(file.path); break;
    case DepthFileKind::kColmapGeometric:
    case DepthFileKind::kColmapPhotometric: depth = readColmapArray(file.path); break;
  }
  if (depth.type() != CV_32FC1) {
    throw Error(file.path + ": a depth map must have one channel, this " + toString(file.kind) + " file has " +
                std::to_string(depth.channels()));
  }
  constexpr float kNone = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < depth.rows; ++y) {
    float* row = depth.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x) {
      if (!std::isfinite(row[x]) || row[x] <= 0.0f) row[x] = kNone;
    }
  }
  return depth;
}

}  // namespace cenote::eval
