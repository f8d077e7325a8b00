// map_file_format.h: the one table from a file name to the format of a map file, used by every
// writer and reader of map files (map_io, `cenote map`, the server's snapshots, the C++ client and
// cenote-cli; clients/python/cenote_client/client.py keeps the same table, checked by its tests).
// The rule: a file's format follows its extension, and a format given explicitly must agree with it.
//
//   extension      format       what the file holds
//   .vdb           vdb          OpenVDB map, loads back exactly
//   .bt            bt           OctoMap binary tree (maximum-likelihood states)
//   .ot            ot           OctoMap ColorOcTree (log-odds and colours)
//   .mesh.ply      mesh-ply     triangle mesh of occupied space
//   .points.ply    points-ply   occupied voxel centres with colours
//   .ply           (either)     a plain .ply names no format by itself: give mesh-ply or points-ply
//   .pcd           points-pcd   occupied voxel centres with colours, PCL's PCD (binary, x y z rgb)
// Extensions compare case-insensitively. Anything else is not a map file and is an error.
// The enum's numbers are admin.proto's SnapshotFormat values (the server and client check it).
// Threads: pure functions.
#pragma once

#include <string>

namespace cenote::mapping {

enum class MapFileFormat { kUnspecified = 0, kVdb = 1, kBt = 2, kOt = 3, kMeshPly = 4, kPointsPly = 5, kPointsPcd = 6 };

// The format the path's extension names, or kUnspecified for a plain .ply and an unknown extension.
MapFileFormat mapFileFormatOf(const std::string& path);

// The one rule: with `requested` kUnspecified, the format the extension names; else `requested`,
// when the extension names it (a plain .ply agrees with mesh-ply and points-ply).
// @throws cenote::Error naming the path and the formats: an unknown extension, a plain .ply without
//         a format, or a format the extension disagrees with ("map.vdb: the extension .vdb means
//         format vdb, not points-ply ...").
MapFileFormat resolveMapFileFormat(const std::string& path, MapFileFormat requested);

// "vdb", "bt", "ot", "mesh-ply", "points-ply", "points-pcd"; "unspecified".
const char* toString(MapFileFormat format);
// The canonical extension: ".vdb", ".bt", ".ot", ".mesh.ply", ".points.ply", ".pcd"; "" for kUnspecified.
const char* extensionOf(MapFileFormat format);
// From toString()'s names ('_' may stand for '-'; "" is kUnspecified).
// @throws cenote::Error listing the names for anything else.
MapFileFormat parseMapFileFormat(const std::string& name);
// The table as one line for messages and help: ".vdb vdb, .bt bt, ..., .pcd points-pcd, .ply ...".
std::string mapFileFormatTable();

}  // namespace cenote::mapping
