#include "mapping/io/map_io.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <filesystem>
#include <fstream>

#include "common/atomic_file.h"
#include "common/error.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("cenote_map_io_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

std::unique_ptr<OccupancyMap> sceneMap() {
  MapConfig c;
  c.voxel_size_m = 0.05;
  auto map = std::make_unique<OccupancyMap>(c);
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.0), Eigen::Vector3d(0, 0, 1)});
  scene.spheres.push_back({Eigen::Vector3d(2.5, 0.0, -0.5), 0.6});
  map->integrate(
      test::renderBatch(scene, test::kCamera, test::lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(2.5, 0, -0.8)), 8.0));
  return map;
}

// Every known voxel of `a` has the same state in `b`, and both know as many voxels.
void expectSameStates(const OccupancyMap& a, const OccupancyMap& b) {
  const MapStats sa = a.stats(), sb = b.stats();
  EXPECT_GT(sa.occupied, 0u) << "premise: the map compared is not empty";
  EXPECT_GT(sa.free, 0u) << "premise: the map compared is not empty";
  EXPECT_EQ(sa.occupied, sb.occupied);
  EXPECT_EQ(sa.free, sb.free);
  auto acc_a = a.constAccessor();
  auto acc_b = b.constAccessor();
  size_t differ = 0;
  for (const BlockIndex& block : acc_a.knownBlocks()) {
    BlockView view;
    acc_a.readBlock(block, view);
    for (int o = 0; o < kBlockVoxels; ++o) {
      if (!((view.known[o >> 6] >> (o & 63)) & 1)) continue;
      const VoxelIndex ijk = voxelOfOffset(block, o);
      if (acc_a.state(ijk) != acc_b.state(ijk)) ++differ;
    }
  }
  EXPECT_EQ(differ, 0u);
}

// Saves `map` to `path` and loads it back: the same states.
void expectRoundTripKeepsStates(const OccupancyMap& map, const std::string& path) {
  saveMap(map, path);
  expectSameStates(map, *loadMap(path));
}

TEST(MapIo, VdbRoundTripKeepsStatesProbabilitiesColoursAndModel) {
  TempDir dir;
  MapConfig c;
  c.voxel_size_m = 0.05;
  c.prob_hit = 0.8;
  OccupancyMap map(c);
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)});
  map.integrate(
      test::renderBatch(scene, test::kCamera, test::lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(3, 0, 0)), 8.0));
  saveMap(map, dir.file("map.vdb"), "odom");
  const auto loaded = loadMap(dir.file("map.vdb"));
  EXPECT_EQ(loaded->config().prob_hit, 0.8);
  EXPECT_EQ(loaded->voxelSize(), 0.05);
  expectSameStates(map, *loaded);
  auto a = map.constAccessor();
  auto b = loaded->constAccessor();
  const VoxelIndex wall = map.toIndex(Eigen::Vector3d(3.01, 0.01, 0.01));
  EXPECT_EQ(a.probability(wall), b.probability(wall));
  std::array<uint8_t, 3> ca{}, cb{};
  ASSERT_TRUE(a.color(wall, ca));
  ASSERT_TRUE(b.color(wall, cb));
  EXPECT_EQ(ca, cb);
  EXPECT_FALSE(fs::exists(temporaryPathFor(dir.file("map.vdb"))));
}

TEST(MapIo, BtRoundTripKeepsStatesAndOctomapReadsIt) {
  TempDir dir;
  const auto map = sceneMap();
  expectRoundTripKeepsStates(*map, dir.file("map.bt"));
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(dir.file("map.bt")));
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
  size_t occupied = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (tree.isNodeOccupied(*it)) occupied += static_cast<size_t>(std::pow(std::lround(it.getSize() / 0.05), 3));
  }
  EXPECT_EQ(occupied, map->stats().occupied);
}

TEST(MapIo, OtRoundTripKeepsStates) {
  TempDir dir;
  expectRoundTripKeepsStates(*sceneMap(), dir.file("map.ot"));
}

TEST(MapIo, MeshAndPointsPlyHaveHeaderAndCounts) {
  TempDir dir;
  const auto map = sceneMap();
  const MeshStats mesh = exportMeshPly(*map, dir.file("mesh.ply"));
  EXPECT_GT(mesh.vertices, 100u);
  EXPECT_GT(mesh.triangles, 100u);
  const size_t points = exportOccupiedPointsPly(*map, dir.file("points.ply"));
  EXPECT_EQ(points, map->stats().occupied);
  std::ifstream in(dir.file("mesh.ply"), std::ios::binary);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  const size_t header_end = [&] {
    std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return all.size();
  }();
  EXPECT_GT(header_end, mesh.vertices * 15 + mesh.triangles * 13);
}

TEST(MapIo, ExportsRefuseAnExtensionNamingAnotherFormat) {
  TempDir dir;
  const auto map = sceneMap();
  for (const char* name : {"m.points.ply", "m.vdb", "m.pcd", "m.xyz"}) {
    EXPECT_THROW(exportMeshPly(*map, dir.file(name)), Error) << name;
    EXPECT_FALSE(fs::exists(dir.file(name))) << name;
  }
  for (const char* name : {"m.mesh.ply", "m.bt", "m.pcd"}) {
    try {
      exportOccupiedPointsPly(*map, dir.file(name));
      ADD_FAILURE() << name << " written as points PLY";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(name) + ": the extension "), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir.file(name))) << name;
  }
  EXPECT_NO_THROW(exportMeshPly(*map, dir.file("m.mesh.ply")));
  EXPECT_EQ(exportOccupiedPointsPly(*map, dir.file("m.points.ply")), map->stats().occupied);
}

TEST(MapIo, OccupiedVoxelCentresAreTheOccupiedVoxels) {
  const auto map = sceneMap();
  const PointBatch centres = occupiedVoxelCentres(*map);
  ASSERT_EQ(centres.size(), map->stats().occupied);
  ASSERT_EQ(centres.colors.size(), centres.size());
  const auto acc = map->constAccessor();
  for (size_t i = 0; i < centres.size(); ++i) {
    const VoxelIndex ijk = map->toIndex(centres.points[i].cast<double>());
    ASSERT_EQ(acc.state(ijk), VoxelState::kOccupied) << "point " << i;
    ASSERT_LT((map->toPoint(ijk).cast<float>() - centres.points[i]).norm(), 1e-6f) << "point " << i << " is no centre";
  }
  EXPECT_TRUE(occupiedVoxelCentres(OccupancyMap(MapConfig{})).empty());
}

TEST(MapIo, ErrorsNameThePath) {
  TempDir dir;
  const auto map = sceneMap();
  EXPECT_THROW(saveMap(*map, dir.file("map.xyz")), Error);
  EXPECT_THROW(loadMap(dir.file("missing.vdb")), Error);
  EXPECT_THROW(saveMap(*map, dir.file("no/such/dir/map.vdb")), Error);
  std::ofstream(dir.file("junk.bt")) << "not a tree";
  try {
    loadMap(dir.file("junk.bt"));
    FAIL() << "junk accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("junk.bt"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cenote::mapping
