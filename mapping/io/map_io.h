// map_io.h: saving, loading and exporting occupancy maps.
//  .vdb  OpenVDB file: grids "log_odds" (active = known) and "color" (packed RGB), file metadata
//        cenote:voxel_size_m, cenote:prob_hit, cenote:prob_miss, cenote:clamp_min, cenote:clamp_max,
//        cenote:occupied_threshold, cenote:max_range_m, cenote:frame_id. Loads back exactly.
//  .bt   OctoMap binary OcTree (read by octovis, octomap_server): maximum-likelihood states only, so a
//        round trip keeps every state but moves probabilities to the clamping bounds.
//  .ot   OctoMap full ColorOcTree: log-odds and colours (octovis shows the colours).
//  mesh  PLY triangle mesh of the occupied voxels' outer surface (OpenVDB volumeToMesh on a 0/1
//        occupancy grid at iso 0.5), vertex colours from the nearest coloured occupied voxel.
//  points PLY of occupied voxel centres with their colours.
// Which extension names which format: map_file_format.h (the one table); every function here refuses
// a path whose extension names another format.
// Every write goes to a temporary file beside the target that is renamed over it at the end: a crash
// never leaves a half-written map. Units: metres, world frame.
// Threads: saving and exporting read the map through a ConstAccessor-like shared lock (integration
// waits); loading builds a new map.
#pragma once

#include <memory>
#include <string>

#include "common/point_batch.h"
#include "mapping/io/map_file_format.h"
#include "mapping/occupancy_map.h"

namespace cenote::mapping {

enum class MapFormat { kVdb, kBt, kOt };

// From the file extension (.vdb, .bt, .ot; map_file_format.h). @throws Error for anything else.
MapFormat mapFormatOf(const std::string& path);

// @throws Error when the file cannot be written (the message names the path and the reason).
void saveMap(const OccupancyMap& map, const std::string& path, const std::string& frame_id = "world");

// The most voxels loadMap() expands a file to (about 1.2 GB of grid): a pruned OctoMap leaf or an
// OpenVDB tile stands for many voxels, so a file of 100 bytes can claim 10^14 of them.
inline constexpr uint64_t kMaxLoadVoxels = uint64_t{1} << 28;
// ... and the grid's bytes per voxel allowed: a dense map's (8^3 floats a leaf), so that voxels
// scattered one per leaf, with a node of 33 kB each above them, are held to the same memory.
inline constexpr uint64_t kLoadBytesPerVoxel = 5;

// Loads .vdb, .bt or .ot. The sensor model comes from the file (.vdb) or from `defaults` (OctoMap
// files keep only the resolution). OctoMap files are checked node by node before OctoMap reads
// them (octree_file_scan.h).
// @throws Error for a missing (NotFoundError), unreadable or foreign file; IoError naming the file
//   and the field for a file cut short, a damaged tree, or more than max_voxels voxels (or a
//   grid of more than max_voxels * kLoadBytesPerVoxel bytes).
// @param max_voxels the most voxels the file may expand to (tests and fuzzing pass less).
std::unique_ptr<OccupancyMap> loadMap(const std::string& path, const MapConfig& defaults = MapConfig{},
                                      uint64_t max_voxels = kMaxLoadVoxels);

struct MeshStats {
  size_t vertices = 0;
  size_t triangles = 0;
};
// `path`: .mesh.ply or a plain .ply. @throws Error for another extension or a failed write.
MeshStats exportMeshPly(const OccupancyMap& map, const std::string& path);
// `path`: .points.ply or a plain .ply. @return the number of points written.
// @throws Error for another extension or a failed write.
size_t exportOccupiedPointsPly(const OccupancyMap& map, const std::string& path);
// The occupied voxels' centres (world metres) with their colours (grey 200 where none was seen), in
// the order of the known blocks; origin zero. What exportOccupiedPointsPly writes, for other formats
// (PCD: io/cloud/pcd_io.h). Empty map: empty batch.
PointBatch occupiedVoxelCentres(const OccupancyMap& map);

}  // namespace cenote::mapping
