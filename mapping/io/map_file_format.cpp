#include "mapping/io/map_file_format.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>

#include "common/enum_names.h"
#include "common/error.h"

namespace cenote::mapping {
namespace {

struct Entry {
  const char* extension;  // lower case, longest first where one ends another (.mesh.ply before .ply)
  MapFileFormat format;
};

// The table of map_file_format.h. A plain ".ply" is not here: it names no format by itself.
constexpr std::array<Entry, 6> kTable = {{{".vdb", MapFileFormat::kVdb},
                                          {".bt", MapFileFormat::kBt},
                                          {".ot", MapFileFormat::kOt},
                                          {".mesh.ply", MapFileFormat::kMeshPly},
                                          {".points.ply", MapFileFormat::kPointsPly},
                                          {".pcd", MapFileFormat::kPointsPcd}}};

std::string lowerFileName(const std::string& path) {
  std::string name = std::filesystem::path(path).filename().string();
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool isPlainPly(const std::string& name) {
  return endsWith(name, ".ply") && mapFileFormatOf(name) == MapFileFormat::kUnspecified;
}

std::string extensionText(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  return ext.empty() ? "no extension" : "the extension " + ext;
}

}  // namespace

MapFileFormat mapFileFormatOf(const std::string& path) {
  const std::string name = lowerFileName(path);
  for (const Entry& e : kTable) {
    if (endsWith(name, e.extension)) return e.format;
  }
  return MapFileFormat::kUnspecified;
}

MapFileFormat resolveMapFileFormat(const std::string& path, MapFileFormat requested) {
  const MapFileFormat named = mapFileFormatOf(path);
  const bool plain_ply = isPlainPly(lowerFileName(path));
  if (requested == MapFileFormat::kUnspecified) {
    if (named != MapFileFormat::kUnspecified) return named;
    if (plain_ply) {
      throw Error(path + ": a .ply file holds a mesh or points: name it .mesh.ply or .points.ply, or give the format "
                         "mesh-ply or points-ply");
    }
    throw Error(path + ": " + extensionText(path) + " names no map file format (" + mapFileFormatTable() + ")");
  }
  if (named == requested) return requested;
  if (plain_ply && (requested == MapFileFormat::kMeshPly || requested == MapFileFormat::kPointsPly)) return requested;
  if (named == MapFileFormat::kUnspecified && !plain_ply) {
    throw Error(path + ": " + extensionText(path) + " does not match format " + toString(requested) +
                ", which is written as " + extensionOf(requested) + " (" + mapFileFormatTable() + ")");
  }
  throw Error(path + ": " + extensionText(path) + " means format " +
              (plain_ply ? std::string("mesh-ply or points-ply") : std::string(toString(named))) + ", not " +
              toString(requested) + " (the format follows the extension: " + mapFileFormatTable() + ")");
}

const char* toString(MapFileFormat format) {
  constexpr EnumName<MapFileFormat> kNames[] = {{MapFileFormat::kUnspecified, "unspecified"},
                                                {MapFileFormat::kVdb, "vdb"},
                                                {MapFileFormat::kBt, "bt"},
                                                {MapFileFormat::kOt, "ot"},
                                                {MapFileFormat::kMeshPly, "mesh-ply"},
                                                {MapFileFormat::kPointsPly, "points-ply"},
                                                {MapFileFormat::kPointsPcd, "points-pcd"}};
  return enumName(kNames, format);
}

const char* extensionOf(MapFileFormat format) {
  for (const Entry& e : kTable) {
    if (e.format == format) return e.extension;
  }
  return "";
}

MapFileFormat parseMapFileFormat(const std::string& name) {
  if (name.empty()) return MapFileFormat::kUnspecified;
  std::string key = name;
  std::replace(key.begin(), key.end(), '_', '-');
  for (const Entry& e : kTable) {
    if (key == toString(e.format)) return e.format;
  }
  throw Error("format " + name + ": expected one of vdb, bt, ot, mesh-ply, points-ply, points-pcd");
}

std::string mapFileFormatTable() {
  std::string text;
  for (const Entry& e : kTable) {
    if (!text.empty()) text += ", ";
    text += std::string(e.extension) + " " + toString(e.format);
  }
  return text + ", .ply mesh-ply or points-ply as given";
}

}  // namespace cenote::mapping
