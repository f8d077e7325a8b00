// Map files that claim more than they hold, or more than a map may load: small crafted OctoMap
// files (the format of octree_file_scan.h, bytes written here) and an OpenVDB file written by
// OpenVDB itself with one active tile; each refused with an IoError naming the file and the field
// before anything is expanded. Real files written by OctoMap and OpenVDB still load.
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <octomap/OcTree.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "common/error.h"
#include "mapping/io/map_io.h"
#include "mapping/io/octree_file_scan.h"

namespace cenote::mapping {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& name) { return (fs::path(::testing::TempDir()) / name).string(); }

std::string writeFile(const std::string& name, const std::string& bytes) {
  const std::string path = scratch(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

const std::string kBtHeader = "# Octomap OcTree binary file\nid OcTree\nsize 9\nres 0.05\ndata\n";
const std::string kOtHeader = "# Octomap OcTree file\nid OcTree\nsize 1\nres 0.05\ndata\n";

// The IoError loadMap throws for the file, or "(no error)".
std::string loadError(const std::string& path) {
  try {
    loadMap(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIoFailure) << e.what();
    return e.what();
  }
  return "(no error)";
}

std::string floatBytes(float value) { return std::string(reinterpret_cast<const char*>(&value), sizeof(value)); }

TEST(MapFileLimits, BtOfEightPrunedLeavesUnderTheRootClaims2e14VoxelsAndIsRefused) {
  // Root with 8 occupied leaf children (bits 01 each): 8 x (2^15)^3 = 2^48 voxels in 2 bytes.
  const std::string path = writeFile("pruned.bt", kBtHeader + "\xAA\xAA");
  ASSERT_LT(fs::file_size(path), 100u);
  EXPECT_EQ(loadError(path), path + ": the tree's 1 nodes have leaves covering 281474976710656 voxels, more than the "
                                    "268435456 a map may load");
}

TEST(MapFileLimits, BtWhoseRootHasNoChildIsOneLeafOfEveryVoxelAndIsRefused) {
  // Bits 00 00: OctoMap keeps the root as a leaf, 2^48 voxels to expand (the fuzzer's find).
  const std::string path = writeFile("bare-root.bt", kBtHeader + std::string(2, '\0'));
  EXPECT_EQ(loadError(path), path + ": the tree's 1 nodes have leaves covering 281474976710656 voxels, more than the "
                                    "268435456 a map may load");
}

TEST(MapFileLimits, BtWhoseNodesGoBelowDepth16IsRefused) {
  // Every child of every node an inner node: OctoMap itself would recurse until the file ends.
  const std::string path = writeFile("deep.bt", kBtHeader + std::string(64, '\xFF'));
  EXPECT_EQ(loadError(path), path + ": OctoMap node 15 has children below depth 16, the deepest level of a tree");
}

TEST(MapFileLimits, BtCutShortIsRefused) {
  const std::string path = writeFile("cut.bt", kBtHeader + std::string(6, '\xFF'));
  EXPECT_EQ(loadError(path), path + ": OctoMap data is truncated at node 3 (0 bytes left of the file)");
}

TEST(MapFileLimits, BtHeaderWithoutAValidResolutionIsRefused) {
  const std::string path = writeFile(
      "res.bt", "# Octomap OcTree binary file\nid OcTree\nsize 1\nres -1\ndata\n" + std::string(2, '\0'));
  EXPECT_EQ(loadError(path), path + ": OctoMap header res must be a finite resolution > 0 m");
  const std::string foreign = writeFile("foreign.bt", "# something else\n");
  EXPECT_EQ(loadError(foreign),
            foreign + ": not an OctoMap binary tree (.bt): the first line is not '# Octomap OcTree binary file'");
}

TEST(MapFileLimits, OtRootLeafClaims2e14VoxelsAndIsRefused) {
  const std::string path = writeFile("root.ot", kOtHeader + floatBytes(2.0f) + std::string(1, '\0'));
  EXPECT_EQ(loadError(path), path + ": the tree's 1 nodes have leaves covering 281474976710656 voxels, more than the "
                                    "268435456 a map may load");
}

TEST(MapFileLimits, OtWithANonFiniteLogOddsIsRefused) {
  const std::string path = writeFile(
      "nan.ot", kOtHeader + floatBytes(std::numeric_limits<float>::quiet_NaN()) + std::string(1, '\0'));
  EXPECT_EQ(loadError(path), path + ": OctoMap node 0 has a log-odds that is not finite");
}

TEST(MapFileLimits, RealOctomapFilesPassTheScanWithTheirVoxelCounts) {
  MapConfig config;
  config.voxel_size_m = 0.1;
  OccupancyMap map(config);
  PointBatch batch;
  batch.origin = Eigen::Vector3d::Zero();
  for (int i = 0; i < 20; ++i) batch.points.push_back(Eigen::Vector3f(1.0f + 0.1f * i, 0.35f, 0.05f));
  map.integrate(batch);
  const MapStats stats = map.stats();
  ASSERT_GT(stats.occupied + stats.free, 20u);
  for (const bool binary : {true, false}) {
    const std::string path = scratch(binary ? "real.bt" : "real.ot");
    saveMap(map, path);
    const OctreeFileSummary summary = scanOctreeFile(path, binary);
    EXPECT_EQ(summary.id, binary ? "OcTree" : "ColorOcTree");
    EXPECT_DOUBLE_EQ(summary.resolution_m, 0.1);
    // cenote writes unpruned trees: one depth-16 leaf per known voxel.
    EXPECT_EQ(summary.leaf_voxels, stats.occupied + stats.free) << path;
    const auto loaded = loadMap(path);
    EXPECT_EQ(loaded->stats().occupied, stats.occupied) << path;
    // The grid leaves the scan counts are the loaded grid's blocks.
    EXPECT_EQ(summary.grid_leaves, loaded->constAccessor().knownBlocks().size()) << path;
    EXPECT_EQ(summary.grid_inner2, 1u) << path;  // all within 1024 voxels
  }
}

TEST(MapFileLimits, FewVoxelsScatteredOnePerGridNodeAreRefusedByTheMemoryTheyWouldTake) {
  // Written by OctoMap itself: 40 occupied voxels 60 m (1200 voxels) apart, each in a grid leaf and
  // upper inner node of its own: 40 x about 40 kB of grid for 40 voxels (the fuzzer's find).
  octomap::OcTree tree(0.05);
  for (int i = 0; i < 40; ++i) tree.updateNode(octomap::point3d(60.0f * static_cast<float>(i - 20), 0.5f, 0.5f), true);
  const std::string path = scratch("scattered.bt");
  ASSERT_TRUE(tree.writeBinary(path));
  const OctreeFileSummary summary = scanOctreeFile(path, true);
  EXPECT_EQ(summary.leaf_voxels, 40u);
  EXPECT_EQ(summary.grid_leaves, 40u);
  EXPECT_EQ(summary.grid_inner1, 40u);
  EXPECT_EQ(summary.grid_inner2, 40u);
  try {
    loadMap(path, MapConfig{}, uint64_t{1} << 16);  // 320 kB of grid at most
    FAIL() << "loaded";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIoFailure);
    EXPECT_NE(std::string(e.what()).find(path + ": the tree's 40 voxels are spread over 40 blocks of 8^3 and would take "),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(" a map may load"), std::string::npos) << e.what();
  }
  EXPECT_EQ(loadMap(path)->stats().occupied, 40u);  // within the default budget
}

TEST(MapFileLimits, VdbWithAnActiveTileBeyondTheLimitIsRefusedBeforeVoxelizing) {
  openvdb::initialize();
  auto log_odds = openvdb::FloatGrid::create(0.0f);
  log_odds->setName("log_odds");
  log_odds->tree().addTile(3, openvdb::Coord(0, 0, 0), 1.0f, true);  // a root tile: 4096^3 voxels
  auto color = openvdb::Int32Grid::create(0);
  color->setName("color");
  openvdb::MetaMap meta;
  for (const char* key : {"cenote:voxel_size_m", "cenote:prob_hit", "cenote:prob_miss", "cenote:clamp_min",
                          "cenote:clamp_max", "cenote:occupied_threshold", "cenote:max_range_m"}) {
    meta.insertMeta(key, openvdb::DoubleMetadata(0.5));
  }
  const std::string path = scratch("tile.vdb");
  openvdb::io::File file(path);
  file.write({log_odds, color}, meta);
  file.close();
  ASSERT_LT(fs::file_size(path), 10000u);
  EXPECT_EQ(loadError(path),
            path + ": grid log_odds has 68719476736 active voxels, more than the 268435456 a map may load");
}

}  // namespace
}  // namespace cenote::mapping
