#include "server/viewer/block_sync.h"

#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>

namespace cenote::server::viewer {
namespace {

// A wall of points at x = 2 m, |y|, |z| <= half_m, seen from the origin.
PointBatch wall(double half_m, double spacing_m) {
  PointBatch batch;
  for (double y = -half_m; y <= half_m; y += spacing_m) {
    for (double z = -half_m; z <= half_m; z += spacing_m) {
      batch.points.emplace_back(2.0f, static_cast<float>(y), static_cast<float>(z));
      batch.colors.push_back({200, 100, 50});
    }
  }
  return batch;
}

// What a client holds after applying SceneUpdates: entity id -> (lod, cubes, voxels).
struct Mirror {
  struct Entity {
    std::string lod;
    size_t cubes = 0;
    uint64_t voxels = 0;
  };
  std::map<std::string, Entity> entities;
  size_t deletions = 0;

  void apply(const std::string& message) {
    const auto update = nlohmann::json::parse(message);
    for (const auto& d : update["deletions"]) {
      deletions += entities.erase(d["id"].get<std::string>());
    }
    for (const auto& e : update["entities"]) {
      Entity entity;
      for (const auto& kv : e["metadata"]) {
        if (kv["key"] == "lod") entity.lod = kv["value"];
        if (kv["key"] == "voxels") entity.voxels = std::stoull(kv["value"].get<std::string>());
      }
      entity.cubes = e["cubes"].size();
      entities[e["id"]] = entity;
    }
  }
  uint64_t fullVoxels() const {
    uint64_t n = 0;
    for (const auto& [id, e] : entities)
      if (e.lod == "full") n += e.cubes;
    return n;
  }
  size_t coarse() const {
    size_t n = 0;
    for (const auto& [id, e] : entities) n += e.lod == "coarse";
    return n;
  }
};

// A map holding a wall of points, and a BlockSync that has marked every block of it to send to a
// client whose view is `mirror`.
struct WallSync {
  mapping::OccupancyMap map{mapping::MapConfig{}};
  BlockSync sync;
  Mirror mirror;

  WallSync(double half_m, ColorBy color_by, double refresh_s = 5.0) : sync("world", color_by, refresh_s) {
    map.integrate(wall(half_m, 0.04));
    markAllKnown();
  }
  // Marks every block the map knows, as for a new client or after a dropped change feed.
  void markAllKnown() {
    const auto access = map.constAccessor();
    sync.markAll(access.knownBlocks());
  }
  // Runs steps until settled; @return the number of steps.
  int settle(double budget_bytes) {
    int steps = 0;
    while (!sync.settled() && steps < 10000) {
      const auto access = map.constAccessor();
      const SyncStep step = sync.next(access, Eigen::Vector3d::Zero(), budget_bytes, 1);
      if (!step.message.empty()) mirror.apply(step.message);
      ++steps;
    }
    return steps;
  }
};

TEST(BlockSync, EmptyMapSendsNothingAndIsSettled) {
  mapping::OccupancyMap map{mapping::MapConfig{}};
  BlockSync sync("world", ColorBy::kImage);
  const auto access = map.constAccessor();
  sync.markAll(access.knownBlocks());
  EXPECT_TRUE(sync.settled());
  EXPECT_TRUE(sync.next(access, Eigen::Vector3d::Zero(), 1e6, 1).message.empty());
}

TEST(BlockSync, AmpleBudgetSendsEveryOccupiedVoxelAtFullDetailInOneStep) {
  WallSync w(1.0, ColorBy::kImage);
  EXPECT_EQ(w.settle(1e9), 1);
  EXPECT_EQ(w.mirror.coarse(), 0u);
  EXPECT_GT(w.map.stats().occupied, 1000u);
  EXPECT_EQ(w.mirror.fullVoxels(), w.map.stats().occupied);
}

TEST(BlockSync, ShortBudgetSendsCoarseBlocksFirstThenRefinesThemWithinTheBudget) {
  WallSync w(1.0, ColorBy::kHeight);
  const double budget = 20000.0;
  size_t largest = 0;
  bool saw_coarse = false;
  int steps = 0;
  while (!w.sync.settled() && steps < 10000) {
    const auto access = w.map.constAccessor();
    const SyncStep step = w.sync.next(access, Eigen::Vector3d::Zero(), budget, 1);
    largest = std::max(largest, step.message.size());
    saw_coarse = saw_coarse || step.coarse_blocks > 0;
    w.mirror.apply(step.message);
    ++steps;
  }
  EXPECT_TRUE(saw_coarse);
  EXPECT_GT(steps, 5);
  // Every message within the budget, but for one block bigger than it (sent alone).
  EXPECT_LE(largest, static_cast<size_t>(budget) + SceneUpdateWriter::entityBytes(mapping::kBlockVoxels));
  EXPECT_EQ(w.mirror.coarse(), 0u);
  EXPECT_EQ(w.mirror.fullVoxels(), w.map.stats().occupied);
}

TEST(BlockSync, ClearedBlocksAreDeletedAndTheMirrorFollowsTheMap) {
  WallSync w(1.0, ColorBy::kImage);
  w.settle(1e9);
  const size_t before = w.mirror.entities.size();
  mapping::Aabb box;
  box.min_m = Eigen::Vector3d(1.5, -2.0, 0.0);
  box.max_m = Eigen::Vector3d(2.5, 2.0, 2.0);
  const mapping::MapDelta delta = w.map.clearBox(box);
  w.sync.markChanged(delta.changed_blocks);
  w.settle(1e9);
  EXPECT_GT(w.mirror.deletions, 0u);
  EXPECT_LT(w.mirror.entities.size(), before);
  EXPECT_EQ(w.mirror.fullVoxels(), w.map.stats().occupied);
}

TEST(BlockSync, AResyncAfterChangesConvergesToTheMapAsItIsNow) {
  WallSync w(0.5, ColorBy::kImage);
  w.settle(1e9);
  w.map.reset();
  PointBatch moved = wall(0.5, 0.04);
  for (auto& p : moved.points) p.y() += 3.0f;
  w.map.integrate(moved);
  w.markAllKnown();  // as after a dropped change feed
  w.settle(1e9);
  EXPECT_EQ(w.mirror.fullVoxels(), w.map.stats().occupied);
  for (const auto& [id, e] : w.mirror.entities) EXPECT_EQ(e.cubes, e.voxels) << id;
}

TEST(BlockSync, ABlockWithTheSameOccupiedVoxelsIsOnlyRefreshedAfterRefreshS) {
  WallSync w(0.5, ColorBy::kImage, 5.0);
  {
    const auto access = w.map.constAccessor();
    const SyncStep first = w.sync.next(access, Eigen::Vector3d::Zero(), 1e9, 1000000000ull);
    ASSERT_GT(first.full_blocks, 0u);
  }
  const mapping::MapDelta again = w.map.integrate(wall(0.5, 0.04));  // the same hits: probabilities rise
  ASSERT_FALSE(again.isEmpty());
  w.sync.markChanged(again.changed_blocks);
  const auto access = w.map.constAccessor();
  const SyncStep soon = w.sync.next(access, Eigen::Vector3d::Zero(), 1e9, 2000000000ull);
  EXPECT_TRUE(soon.message.empty());
  EXPECT_TRUE(w.sync.settled());
  const size_t stale = w.sync.staleBlocks();
  EXPECT_GT(stale, 0u);
  const SyncStep later = w.sync.next(access, Eigen::Vector3d::Zero(), 1e9, 6000000001ull);
  EXPECT_EQ(later.full_blocks, stale);
  EXPECT_EQ(w.sync.staleBlocks(), 0u);
}

}  // namespace
}  // namespace cenote::server::viewer
