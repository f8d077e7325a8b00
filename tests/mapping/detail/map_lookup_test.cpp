// map_lookup_test: the map's own lookup structures (the block -> leaf index, the colour store)
// answer exactly as the OpenVDB tree and the colours they shadow, after every kind of change:
// integration, clearing a box or sphere (which edit them in place), cropping, resetting.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "mapping/detail/leaf_index.h"
#include "mapping/detail/map_impl.h"
#include "mapping/occupancy_map.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping {
namespace {

TEST(LeafIndex, FindsWhatWasInsertedAndNotWhatWasErased) {
  // Blocks packed into a few hash runs (a small cube, a small table), inserted and erased at random;
  // find() checked against a std::map after every step, for every block ever used.
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coord(-3, 3);
  detail::LeafIndex index;
  std::map<uint64_t, const float*> expected;
  std::vector<BlockIndex> used;
  static float values[64];
  static uint64_t known[8];
  for (int step = 0; step < 4000; ++step) {
    const BlockIndex b(coord(rng), coord(rng), coord(rng));
    used.push_back(b);
    const uint64_t key = detail::packIndex(b);
    if (rng() % 3 != 0) {
      index.insert(b, detail::LeafRef{values + step % 64, known});
      expected[key] = values + step % 64;
    } else {
      index.erase(b);
      expected.erase(key);
    }
    ASSERT_EQ(index.size(), expected.size()) << "step " << step;
    if (step % 50 != 0) continue;
    for (const BlockIndex& u : used) {
      const detail::LeafRef* ref = index.find(u);
      const auto it = expected.find(detail::packIndex(u));
      ASSERT_EQ(ref != nullptr, it != expected.end()) << "step " << step << ", block " << u.transpose();
      if (ref != nullptr) {
        EXPECT_EQ(ref->values, it->second) << "step " << step << ", block " << u.transpose();
      }
    }
  }
}

struct VoxelSnapshot {
  bool known = false;
  float log_odds = 0.0f;
  bool has_color = false;
  std::array<uint8_t, 3> rgb{};
};

// Every voxel of a box around the map, by index within it.
std::vector<VoxelSnapshot> snapshot(const OccupancyMap& map, const VoxelBox& region) {
  std::vector<VoxelSnapshot> out;
  const auto acc = map.constAccessor();
  for (int x = region.min.x(); x <= region.max.x(); ++x) {
    for (int y = region.min.y(); y <= region.max.y(); ++y) {
      for (int z = region.min.z(); z <= region.max.z(); ++z) {
        VoxelSnapshot v;
        v.known = acc.logOdds(VoxelIndex(x, y, z), v.log_odds);
        v.has_color = acc.color(VoxelIndex(x, y, z), v.rgb);
        out.push_back(v);
      }
    }
  }
  return out;
}

// Lookups through the accessor (leaf index) equal OpenVDB's probeValue on the tree, voxel by voxel.
void expectLookupsEqualTree(const OccupancyMap& map, const VoxelBox& region, const std::string& when) {
  const auto& tree = detail::MapAccess::of(map).log_odds->constTree();
  const auto acc = map.constAccessor();
  size_t known = 0;
  for (int x = region.min.x(); x <= region.max.x(); ++x) {
    for (int y = region.min.y(); y <= region.max.y(); ++y) {
      for (int z = region.min.z(); z <= region.max.z(); ++z) {
        float tree_l = 0.0f, ours_l = 0.0f;
        const bool tree_known = tree.probeValue(openvdb::Coord(x, y, z), tree_l);
        const bool ours_known = acc.logOdds(VoxelIndex(x, y, z), ours_l);
        ASSERT_EQ(ours_known, tree_known) << when << ", voxel " << x << " " << y << " " << z;
        if (tree_known) {
          ASSERT_EQ(ours_l, tree_l) << when << ", voxel " << x << " " << y << " " << z;
        }
        known += tree_known;
      }
    }
  }
  if (when != "reset") {
    EXPECT_GT(known, 1000u) << when;
  }
}

TEST(MapLookup, IndexAndColoursFollowTheTreeThroughClearingCroppingAndReset) {
  MapConfig config;
  config.voxel_size_m = 0.1;
  config.num_threads = 2;
  OccupancyMap map(config);
  test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -1.5), Eigen::Vector3d(0.1, 0.0, 1.0).normalized()});
  scene.spheres.push_back({Eigen::Vector3d(3.0, 0.5, -1.2), 0.6});
  for (int f = 0; f < 3; ++f) {
    const Eigen::Vector3d position(0.5 * f, 0.0, 0.0);
    map.integrate(
        test::renderBatch(scene, test::kCamera, test::lookAt(position, position + Eigen::Vector3d(1.0, 0.0, -0.6)), 8.0));
  }
  VoxelBox region = map.stats().bounds;
  region.min -= VoxelIndex::Constant(9);
  region.max += VoxelIndex::Constant(9);
  expectLookupsEqualTree(map, region, "integrated");

  // Each clear: lookups still equal the tree, and every voxel outside the cleared shape keeps its
  // state, value and colour, while inside it is unknown and colourless. The colour store keeps the
  // entries of blocks it emptied until they are more than half of its entries, then holds only the
  // blocks with colours left (color_store.h ColorStore::eraseIf): its entry count after the clear
  // is the one that rule gives from the count before and the blocks that kept colours.
  const detail::ColorStore& colours = detail::MapAccess::of(map).color;
  int compactions = 0, clears_keeping_empty_blocks = 0;
  auto check = [&](const std::string& when, auto&& inside, auto&& clear) {
    const std::vector<VoxelSnapshot> before = snapshot(map, region);
    const size_t entries_before = colours.numBlocks();
    clear();
    expectLookupsEqualTree(map, region, when);
    std::set<uint64_t> coloured_blocks;
    colours.forEach([&](const VoxelIndex& ijk, int32_t) { coloured_blocks.insert(detail::packIndex(blockOf(ijk))); });
    const size_t emptied = entries_before - coloured_blocks.size();
    const bool compacts = 2 * emptied > entries_before;
    EXPECT_EQ(colours.numBlocks(), compacts ? coloured_blocks.size() : entries_before)
        << when << ": " << entries_before << " entries before, " << coloured_blocks.size() << " blocks with colours after";
    compactions += compacts;
    clears_keeping_empty_blocks += !compacts && emptied > 0;
    const std::vector<VoxelSnapshot> after = snapshot(map, region);
    size_t i = 0, removed_colours = 0, kept_colours = 0;
    for (int x = region.min.x(); x <= region.max.x(); ++x) {
      for (int y = region.min.y(); y <= region.max.y(); ++y) {
        for (int z = region.min.z(); z <= region.max.z(); ++z, ++i) {
          const std::string at = when + ", voxel " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z);
          if (inside(map.toPoint(VoxelIndex(x, y, z)))) {
            ASSERT_FALSE(after[i].known) << at;
            ASSERT_FALSE(after[i].has_color) << at;
            removed_colours += before[i].has_color;
            continue;
          }
          ASSERT_EQ(after[i].known, before[i].known) << at;
          ASSERT_EQ(after[i].log_odds, before[i].log_odds) << at;
          ASSERT_EQ(after[i].has_color, before[i].has_color) << at;
          ASSERT_EQ(after[i].rgb, before[i].rgb) << at;
          kept_colours += after[i].has_color;
        }
      }
    }
    if (when == "clearBox" || when == "clearSphere" || when == "crop") {
      EXPECT_GT(removed_colours, 0u) << when;
      EXPECT_GT(kept_colours, 0u) << when;
    }
  };
  Aabb box;
  box.min_m = Eigen::Vector3d(2.0, -1.0, -3.0);
  box.max_m = Eigen::Vector3d(3.2, 0.7, 0.0);
  check(
      "clearBox", [&](const Eigen::Vector3d& c) { return box.contains(c); }, [&] { map.clearBox(box); });
  const Eigen::Vector3d centre(4.0, 1.0, -1.5);
  check(
      "clearSphere", [&](const Eigen::Vector3d& c) { return (c - centre).norm() <= 1.0; },
      [&] { map.clearSphere(centre, 1.0); });
  // Many small clears: blocks lose all their colours one after another (the store compacts).
  for (int k = 0; k < 12; ++k) {
    const Eigen::Vector3d at(5.0 + 0.4 * k, -1.0 + 0.2 * k, -1.6);
    check(
        "small sphere " + std::to_string(k), [&](const Eigen::Vector3d& c) { return (c - at).norm() <= 0.35; },
        [&] { map.clearSphere(at, 0.35); });
  }
  check(
      "crop", [&](const Eigen::Vector3d& c) { return c.norm() > 4.0; },
      [&] { map.cropToRadius(Eigen::Vector3d::Zero(), 4.0); });
  // Integrating again after clearing reuses and re-creates leaves and colour blocks.
  map.integrate(test::renderBatch(scene, test::kCamera,
                                  test::lookAt(Eigen::Vector3d(0.2, 0.1, 0.0), Eigen::Vector3d(2.0, 0.1, -1.5)), 8.0));
  expectLookupsEqualTree(map, region, "integrated again");
  check(
      "reset", [](const Eigen::Vector3d&) { return true; }, [&] { map.reset(); });
  // Reset leaves the store as a new one; both ways of eraseIf ran along the way.
  EXPECT_EQ(colours.numBlocks(), 0u);
  EXPECT_EQ(colours.memoryBytes(), detail::ColorStore().memoryBytes());
  EXPECT_GE(compactions, 2);
  EXPECT_GE(clears_keeping_empty_blocks, 1);
}

}  // namespace
}  // namespace cenote::mapping
