#include "mapping/io/map_io.h"

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/atomic_file.h"
#include "common/error.h"
#include "common/size_format.h"
#include "io/cloud/ply_io.h"
#include "mapping/detail/map_impl.h"
#include "mapping/detail/mask_bits.h"
#include "mapping/io/octree_file_scan.h"

namespace cenote::mapping {
namespace {

using openvdb::Coord;

// A file buffer that remembers its first failed write. OpenVDB writes part of a .vdb through the
// stream's buffer (sputn), and a buffer's failures never reach the stream's state: a write cut
// short by a full disk or a file-size limit left the stream good and the truncated file was
// committed. Checking the buffer catches every writer, whichever way it writes.
class CheckedFileBuf : public std::filebuf {
 public:
  // errno of the first failed write; 0 when every write went through.
  int error() const { return error_; }

 protected:
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    const std::streamsize written = std::filebuf::xsputn(s, n);
    if (written != n) noteFailure();
    return written;
  }
  int_type overflow(int_type c) override {
    const int_type result = std::filebuf::overflow(c);
    if (traits_type::eq_int_type(result, traits_type::eof())) noteFailure();
    return result;
  }
  int sync() override {
    const int result = std::filebuf::sync();
    if (result != 0) noteFailure();
    return result;
  }

 private:
  void noteFailure() {
    if (error_ == 0) error_ = errno != 0 ? errno : EIO;
  }
  int error_ = 0;
};

// Writes `temp` through write(std::ostream&) and checks every write of it, flushed and closed:
// OpenVDB's and OctoMap's own file writers never look. @throws ResourceExhaustedError (ENOSPC,
// EDQUOT, EFBIG) or IoError naming `path`.
template <typename Write>
void writeCheckedStream(const std::string& path, const std::string& temp, Write&& write) {
  CheckedFileBuf buffer;
  if (!buffer.open(temp, std::ios::out | std::ios::binary | std::ios::trunc)) {
    throwWriteError(path, "cannot create file", errno);
  }
  std::ostream out(&buffer);
  const bool written = write(out);
  out.flush();
  const bool closed = buffer.close() != nullptr;
  const int err = buffer.error() != 0 ? buffer.error() : (closed ? 0 : errno);
  if (!written || err != 0 || out.fail() || !closed) {
    throwWriteError(path, std::string("write failed (") + (err ? std::strerror(err) : "disk full?") + ")", err);
  }
}

// OpenVDB's File::write, on a stream of ours (its Archive::write is protected).
class VdbStreamWriter : public openvdb::io::File {
 public:
  using openvdb::io::File::File;
  void writeTo(std::ostream& os, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) const {
    openvdb::io::Archive::write(os, grids, /*seekable=*/true, meta);
  }
};

// The map as the grids of a .vdb file, readable by any OpenVDB tool: log_odds (a standard FloatGrid
// holding copies of the map's leaves) and color (Int32Grid, active where some point hit).
// Call under the map's shared lock.
openvdb::GridPtrVec toFileGrids(const detail::MapImpl& impl, double voxel_size_m) {
  auto log_odds = openvdb::FloatGrid::create(0.0f);
  log_odds->setTransform(detail::makeTransform(voxel_size_m));
  log_odds->setName("log_odds");
  log_odds->setGridClass(openvdb::GRID_UNKNOWN);
  for (auto leaf = impl.log_odds->constTree().cbeginLeaf(); leaf; ++leaf) {
    log_odds->tree().addLeaf(new openvdb::FloatTree::LeafNodeType(*leaf));
  }
  auto color = openvdb::Int32Grid::create(0);
  color->setTransform(detail::makeTransform(voxel_size_m));
  color->setName("color");
  auto acc = color->getAccessor();
  impl.color.forEach(
      [&](const VoxelIndex& ijk, int32_t packed) { acc.setValueOn(Coord(ijk.x(), ijk.y(), ijk.z()), packed); });
  return {log_odds, color};
}

// Fills an empty map from the grids of a .vdb file (tiles are split into voxels).
// @throws Error for a voxel beyond the +-kMaxVoxelIndex per axis the map holds (voxel_types.h).
void fromFileGrids(openvdb::FloatGrid& log_odds, openvdb::Int32Grid& color, detail::MapImpl& impl,
                   const std::string& path) {
  log_odds.tree().voxelizeActiveTiles(false);
  for (auto leaf = log_odds.tree().cbeginLeaf(); leaf; ++leaf) {
    const Coord o = leaf->origin();
    const VoxelIndex first(o.x(), o.y(), o.z());
    if (!inMapRange(first) || !inMapRange(first + VoxelIndex::Constant(kBlockSide - 1))) {
      throw Error(path + ": voxel (" + std::to_string(o.x()) + ", " + std::to_string(o.y()) + ", " + std::to_string(o.z()) +
                  ") lies beyond the " + std::to_string(kMaxVoxelIndex) + " voxels per axis a map holds");
    }
    impl.log_odds->tree().addLeaf(new openvdb::FloatTree::LeafNodeType(*leaf));
  }
  impl.reindexLeaves();
  for (auto it = color.tree().cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto xyz = box.begin(); xyz; ++xyz) {
      const VoxelIndex ijk((*xyz).x(), (*xyz).y(), (*xyz).z());
      if (!inMapRange(ijk)) {
        throw Error(path + ": coloured voxel (" + std::to_string(ijk.x()) + ", " + std::to_string(ijk.y()) + ", " +
                    std::to_string(ijk.z()) + ") lies beyond the " + std::to_string(kMaxVoxelIndex) +
                    " voxels per axis a map holds");
      }
      impl.color.set(ijk, *it);
    }
  }
}

// Known voxels with their log-odds, under the map's shared lock.
template <typename Visit>
void forEachKnown(const OccupancyMap& map, Visit&& visit) {
  const auto acc = map.constAccessor();
  BlockView view;
  for (const BlockIndex& block : acc.knownBlocks()) {
    if (!acc.readBlock(block, view)) continue;
    detail::forEachSetBit(view.known, [&](int o) { visit(voxelOfOffset(block, o), view.log_odds[o], acc); });
  }
}

octomap::OcTreeKey keyOf(const VoxelIndex& ijk) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(ijk.x() + 32768),
                            static_cast<octomap::key_type>(ijk.y() + 32768),
                            static_cast<octomap::key_type>(ijk.z() + 32768));
}

void checkOctomapRange(const VoxelIndex& ijk) {
  if ((ijk.array() < -32768).any() || (ijk.array() > 32767).any()) {
    throw Error("map: voxel (" + std::to_string(ijk.x()) + ", " + std::to_string(ijk.y()) + ", " + std::to_string(ijk.z()) +
                ") lies outside OctoMap's 2^16 voxels per axis");
  }
}

template <typename Tree>
void setSensorModel(Tree& tree, const MapConfig& c) {
  tree.setProbHit(c.prob_hit);
  tree.setProbMiss(c.prob_miss);
  tree.setClampingThresMin(c.clamp_min);
  tree.setClampingThresMax(c.clamp_max);
  tree.setOccupancyThres(c.occupied_threshold);
}

void saveOctomap(const OccupancyMap& map, const std::string& path, bool full) {
  writeAtomically(path, Durability::kDurable, [&](const std::string& temp) {
    if (full) {
      octomap::ColorOcTree tree(map.voxelSize());
      setSensorModel(tree, map.config());
      forEachKnown(map, [&](const VoxelIndex& ijk, float l, const OccupancyMap::ConstAccessor& acc) {
        checkOctomapRange(ijk);
        auto* node = tree.setNodeValue(keyOf(ijk), l, true);
        std::array<uint8_t, 3> rgb;
        if (acc.color(ijk, rgb)) node->setColor(rgb[0], rgb[1], rgb[2]);
      });
      tree.updateInnerOccupancy();
      writeCheckedStream(path, temp, [&](std::ostream& out) { return tree.write(out); });
    } else {
      octomap::OcTree tree(map.voxelSize());
      setSensorModel(tree, map.config());
      forEachKnown(map, [&](const VoxelIndex& ijk, float l, const OccupancyMap::ConstAccessor&) {
        checkOctomapRange(ijk);
        tree.setNodeValue(keyOf(ijk), l, true);
      });
      tree.updateInnerOccupancy();
      writeCheckedStream(path, temp, [&](std::ostream& out) { return tree.writeBinary(out); });
    }
  });
}

void saveVdb(const OccupancyMap& map, const std::string& path, const std::string& frame_id) {
  const detail::MapImpl& impl = detail::MapAccess::of(map);
  openvdb::GridPtrVec grids;
  {
    std::shared_lock<detail::FairSharedMutex> lock(impl.grid_mutex);
    grids = toFileGrids(impl, map.voxelSize());
  }
  const MapConfig& c = map.config();
  openvdb::MetaMap meta;
  meta.insertMeta("cenote:voxel_size_m", openvdb::DoubleMetadata(c.voxel_size_m));
  meta.insertMeta("cenote:prob_hit", openvdb::DoubleMetadata(c.prob_hit));
  meta.insertMeta("cenote:prob_miss", openvdb::DoubleMetadata(c.prob_miss));
  meta.insertMeta("cenote:clamp_min", openvdb::DoubleMetadata(c.clamp_min));
  meta.insertMeta("cenote:clamp_max", openvdb::DoubleMetadata(c.clamp_max));
  meta.insertMeta("cenote:occupied_threshold", openvdb::DoubleMetadata(c.occupied_threshold));
  meta.insertMeta("cenote:max_range_m", openvdb::DoubleMetadata(c.max_range_m));
  meta.insertMeta("cenote:frame_id", openvdb::StringMetadata(frame_id));
  writeAtomically(path, Durability::kDurable, [&](const std::string& temp) {
    writeCheckedStream(path, temp, [&](std::ostream& out) {
      VdbStreamWriter(temp).writeTo(out, grids, meta);
      return true;
    });
  });
}

double metaDouble(const openvdb::MetaMap& meta, const std::string& key, const std::string& path) {
  auto value = meta.getMetadata<openvdb::DoubleMetadata>(key);
  if (!value) throw Error(path + ": not a cenote map (no " + key + " metadata)");
  return value->value();
}

std::unique_ptr<OccupancyMap> loadVdb(const std::string& path, const MapConfig& defaults, uint64_t max_voxels) {
  openvdb::io::File file(path);
  try {
    file.open();
  } catch (const openvdb::Exception& e) {
    throw Error("cannot read " + path + ": " + e.what());
  }
  openvdb::MetaMap::Ptr meta;
  openvdb::FloatGrid::Ptr log_odds;
  openvdb::Int32Grid::Ptr color;
  try {
    meta = file.getMetadata();
    log_odds = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("log_odds"));
    color = openvdb::gridPtrCast<openvdb::Int32Grid>(file.readGrid("color"));
    file.close();
  } catch (const openvdb::Exception& e) {
    throw IoError("cannot read " + path + ": " + e.what());
  }
  if (!log_odds || !color) throw Error(path + ": grids log_odds (float) and color (int32) expected");
  // Counted with tiles as they are, before any is expanded: one active tile of a small file can
  // stand for 2^36 voxels.
  for (const auto& [name, voxels] : {std::pair<const char*, uint64_t>{"log_odds", log_odds->activeVoxelCount()},
                                     std::pair<const char*, uint64_t>{"color", color->activeVoxelCount()}}) {
    if (voxels > max_voxels) {
      throw IoError(path + ": grid " + name + " has " + std::to_string(voxels) + " active voxels, more than the " +
                    std::to_string(max_voxels) + " a map may load");
    }
  }
  MapConfig c = defaults;
  c.voxel_size_m = metaDouble(*meta, "cenote:voxel_size_m", path);
  c.prob_hit = metaDouble(*meta, "cenote:prob_hit", path);
  c.prob_miss = metaDouble(*meta, "cenote:prob_miss", path);
  c.clamp_min = metaDouble(*meta, "cenote:clamp_min", path);
  c.clamp_max = metaDouble(*meta, "cenote:clamp_max", path);
  c.occupied_threshold = metaDouble(*meta, "cenote:occupied_threshold", path);
  c.max_range_m = metaDouble(*meta, "cenote:max_range_m", path);
  auto map = std::make_unique<OccupancyMap>(c);
  detail::MapImpl& impl = detail::MapAccess::of(*map);
  std::unique_lock<detail::FairSharedMutex> lock(impl.grid_mutex);
  fromFileGrids(*log_odds, *color, impl, path);
  return map;
}

template <typename Tree>
std::unique_ptr<OccupancyMap> fromOctree(const Tree& tree, const MapConfig& defaults) {
  MapConfig c = defaults;
  c.voxel_size_m = tree.getResolution();
  auto map = std::make_unique<OccupancyMap>(c);
  detail::MapImpl& impl = detail::MapAccess::of(*map);
  std::unique_lock<detail::FairSharedMutex> lock(impl.grid_mutex);
  auto acc = impl.log_odds->getAccessor();
  const double s = c.voxel_size_m;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / s));
    const octomap::point3d centre = it.getCoordinate();
    const VoxelIndex first(static_cast<int>(std::floor((centre.x() - size / 2 + s / 2) / s)),
                           static_cast<int>(std::floor((centre.y() - size / 2 + s / 2) / s)),
                           static_cast<int>(std::floor((centre.z() - size / 2 + s / 2) / s)));
    const float l = it->getLogOdds();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          const Coord xyz(first.x() + i, first.y() + j, first.z() + k);
          acc.setValueOn(xyz, l);
          if constexpr (std::is_same_v<Tree, octomap::ColorOcTree>) {
            const auto col = it->getColor();
            if (tree.isNodeOccupied(*it))
              impl.color.set(first + VoxelIndex(i, j, k), detail::packColor({col.r, col.g, col.b}, 1));
          }
        }
      }
    }
  }
  impl.reindexLeaves();
  return map;
}

std::unique_ptr<OccupancyMap> loadOctomap(const std::string& path, const MapConfig& defaults, bool binary,
                                          uint64_t max_voxels) {
  // OctoMap's readers trust the file (octree_file_scan.h): its structure is checked first.
  const OctreeFileSummary summary = scanOctreeFile(path, binary);
  if (summary.leaf_voxels > max_voxels) {
    throw IoError(path + ": the tree's " + std::to_string(summary.nodes) + " nodes have leaves covering " +
                  std::to_string(summary.leaf_voxels) + " voxels, more than the " + std::to_string(max_voxels) +
                  " a map may load");
  }
  // The voxels may also be few but scattered, one per grid leaf: the memory is what is bounded.
  if (summary.gridBytes() > max_voxels * kLoadBytesPerVoxel) {
    throw IoError(path + ": the tree's " + std::to_string(summary.leaf_voxels) + " voxels are spread over " +
                  std::to_string(summary.grid_leaves) + " blocks of 8^3 and would take " +
                  formatBytes(static_cast<double>(summary.gridBytes())) + " of grid, more than the " +
                  formatBytes(static_cast<double>(max_voxels * kLoadBytesPerVoxel)) + " a map may load");
  }
  // OctoMap reads the nodes the scan checked, from where the scan found them, into a tree made
  // from the header as the scan read it: its own header parser, which may read a malformed header
  // otherwise, never runs.
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(summary.data_offset));
  if (!in) throw IoError("cannot read " + path + ": " + std::strerror(errno));
  auto read = [&](auto& tree) {
    if (summary.header_size > 0) binary ? tree.readBinaryData(in) : tree.readData(in);
    if (!in) throw IoError(path + ": OctoMap could not read the tree's nodes");
    return fromOctree(tree, defaults);
  };
  if (binary || summary.id == "OcTree") {
    octomap::OcTree tree(summary.resolution_m);
    return read(tree);
  }
  octomap::ColorOcTree tree(summary.resolution_m);
  return read(tree);
}

struct PlyVertex {
  float x, y, z;
  uint8_t r, g, b;
};

void writePly(const std::string& path, const std::vector<PlyVertex>& vertices,
              const std::vector<std::array<uint32_t, 3>>& triangles) {
  // io/cloud/ply_io.h writes every PLY of cenote (OpenCV-free target cenote_io_cloud).
  std::vector<Eigen::Vector3f> points(vertices.size());
  std::vector<std::array<uint8_t, 3>> colors(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    points[i] = Eigen::Vector3f(vertices[i].x, vertices[i].y, vertices[i].z);
    colors[i] = {vertices[i].r, vertices[i].g, vertices[i].b};
  }
  io::writePlyMesh(path, points, colors, triangles, "cenote occupancy map");
}

}  // namespace

MapFormat mapFormatOf(const std::string& path) {
  switch (mapFileFormatOf(path)) {
    case MapFileFormat::kVdb: return MapFormat::kVdb;
    case MapFileFormat::kBt: return MapFormat::kBt;
    case MapFileFormat::kOt: return MapFormat::kOt;
    default: throw Error("map file " + path + ": extension must be .vdb, .bt or .ot");
  }
}

void saveMap(const OccupancyMap& map, const std::string& path, const std::string& frame_id) {
  switch (mapFormatOf(path)) {
    case MapFormat::kVdb: return saveVdb(map, path, frame_id);
    case MapFormat::kBt: return saveOctomap(map, path, false);
    case MapFormat::kOt: return saveOctomap(map, path, true);
  }
}

std::unique_ptr<OccupancyMap> loadMap(const std::string& path, const MapConfig& defaults, uint64_t max_voxels) {
  const MapFormat format = mapFormatOf(path);
  if (!std::filesystem::exists(path)) throw NotFoundError("cannot read " + path + ": no such file");
  openvdb::initialize();
  switch (format) {
    case MapFormat::kVdb: return loadVdb(path, defaults, max_voxels);
    case MapFormat::kBt: return loadOctomap(path, defaults, true, max_voxels);
    case MapFormat::kOt: return loadOctomap(path, defaults, false, max_voxels);
  }
  return nullptr;
}

PointBatch occupiedVoxelCentres(const OccupancyMap& map) {
  PointBatch batch;
  forEachKnown(map, [&](const VoxelIndex& ijk, float l, const OccupancyMap::ConstAccessor& acc) {
    if (!map.model().isOccupied(l)) return;
    std::array<uint8_t, 3> rgb{200, 200, 200};
    acc.color(ijk, rgb);
    batch.points.push_back(map.toPoint(ijk).cast<float>());
    batch.colors.push_back(rgb);
  });
  return batch;
}

size_t exportOccupiedPointsPly(const OccupancyMap& map, const std::string& path) {
  resolveMapFileFormat(path, MapFileFormat::kPointsPly);
  const PointBatch centres = occupiedVoxelCentres(map);
  std::vector<PlyVertex> vertices(centres.size());
  for (size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3f& p = centres.points[i];
    vertices[i] = {p.x(), p.y(), p.z(), centres.colors[i][0], centres.colors[i][1], centres.colors[i][2]};
  }
  writePly(path, vertices, {});
  return vertices.size();
}

MeshStats exportMeshPly(const OccupancyMap& map, const std::string& path) {
  resolveMapFileFormat(path, MapFileFormat::kMeshPly);
  auto occupancy = openvdb::FloatGrid::create(0.0f);
  occupancy->setTransform(detail::makeTransform(map.voxelSize()));
  {
    auto acc = occupancy->getAccessor();
    forEachKnown(map, [&](const VoxelIndex& ijk, float l, const OccupancyMap::ConstAccessor&) {
      if (map.model().isOccupied(l)) acc.setValueOn(Coord(ijk.x(), ijk.y(), ijk.z()), 1.0f);
    });
  }
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*occupancy, points, triangles, quads, 0.5, 0.0);
  std::vector<PlyVertex> vertices(points.size());
  {
    const auto acc = map.constAccessor();
    const double s = map.voxelSize();
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d p(points[i].x(), points[i].y(), points[i].z());
      // Colour of the nearest coloured voxel in the 3x3x3 around the vertex.
      const VoxelIndex base = map.toIndex(p);
      std::array<uint8_t, 3> best{200, 200, 200};
      double best_d2 = 1e30;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const VoxelIndex ijk = base + VoxelIndex(dx, dy, dz);
            std::array<uint8_t, 3> rgb;
            if (!acc.color(ijk, rgb)) continue;
            const double d2 = (map.toPoint(ijk) - p).squaredNorm();
            if (d2 < best_d2) {
              best_d2 = d2;
              best = rgb;
            }
          }
      (void)s;
      vertices[i] = {points[i].x(), points[i].y(), points[i].z(), best[0], best[1], best[2]};
    }
  }
  std::vector<std::array<uint32_t, 3>> faces;
  faces.reserve(triangles.size() + 2 * quads.size());
  for (const auto& t : triangles) faces.push_back({t[0], t[1], t[2]});
  for (const auto& q : quads) {
    faces.push_back({q[0], q[1], q[2]});
    faces.push_back({q[0], q[2], q[3]});
  }
  writePly(path, vertices, faces);
  return {vertices.size(), faces.size()};
}

}  // namespace cenote::mapping
