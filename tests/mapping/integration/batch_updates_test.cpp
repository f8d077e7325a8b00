// BatchUpdates (integration/batch_updates.h): the dense block window of setWindow() finds the same
// blocks, in the same slots, as the hash table alone, and forgets its blocks between builds.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "mapping/integration/batch_updates.h"

namespace cenote::mapping {
namespace {

// Sets bit (k % 512) of the free mask of each block in `blocks`, the k-th call, through masksOf.
void touch(BatchUpdates& updates, const std::vector<BlockIndex>& blocks) {
  for (size_t k = 0; k < blocks.size(); ++k) {
    const int bit = static_cast<int>(k % kBlockVoxels);
    updates.masksOf(blocks[k])->free[bit >> 6] |= 1ull << (bit & 63);
  }
}

// Every block and its masks after finish(), as "(x, y, z): free words" lines.
std::vector<std::string> listing(BatchUpdates& updates) {
  updates.finish(EndpointSet(), false);
  std::vector<std::string> out;
  for (size_t i = 0; i < updates.numBlocks(); ++i) {
    const BlockIndex& b = updates.block(i);
    std::string line = "(";
    for (int a = 0; a < 3; ++a) line.append(std::to_string(b[a])).append(a < 2 ? ", " : "):");
    for (uint64_t w : updates.masks(i).free) line.append(" ").append(std::to_string(w));
    out.push_back(line);
  }
  return out;
}

// Random blocks in [-6, 6)^3, repeats included: some inside the window below, some outside.
std::vector<BlockIndex> randomBlocks(uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coordinate(-6, 5);
  std::vector<BlockIndex> blocks;
  for (int i = 0; i < n; ++i) blocks.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  return blocks;
}

TEST(BatchUpdates, WindowFindsTheSameBlocksAsTheHashTable) {
  const VoxelBox window{BlockIndex(-2, -3, -1), BlockIndex(3, 2, 4)};
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const std::vector<BlockIndex> blocks = randomBlocks(seed, 3000);
    BatchUpdates hashed, windowed;
    hashed.clearMasks();
    windowed.clearMasks();
    windowed.setWindow(window);
    touch(hashed, blocks);
    touch(windowed, blocks);
    EXPECT_EQ(listing(windowed), listing(hashed)) << "seed " << seed;
  }
}

TEST(BatchUpdates, WindowForgetsItsBlocksBetweenBuilds) {
  // The second build reuses the window's memory with another box: a cell left from the first
  // build would hand out a slot of a block that this build does not hold.
  BatchUpdates windowed, hashed;
  windowed.clearMasks();
  windowed.setWindow(VoxelBox{BlockIndex(-6, -6, -6), BlockIndex(5, 5, 5)});
  touch(windowed, randomBlocks(7, 2000));
  windowed.clearMasks();
  windowed.setWindow(VoxelBox{BlockIndex(-4, -5, -6), BlockIndex(5, 3, 2)});
  const std::vector<BlockIndex> second = randomBlocks(8, 500);
  touch(windowed, second);
  hashed.clearMasks();
  touch(hashed, second);
  EXPECT_EQ(listing(windowed), listing(hashed));
}

TEST(BatchUpdates, SwappedMasksLeaveNoWindowBehind) {
  // RayBatch takes chunk 0's masks over with swapMasks: the chunk's next build must not find the
  // blocks it handed over.
  BatchUpdates chunk, result, hashed;
  chunk.clearMasks();
  chunk.setWindow(VoxelBox{BlockIndex(-6, -6, -6), BlockIndex(5, 5, 5)});
  touch(chunk, randomBlocks(9, 1000));
  result.swapMasks(chunk);
  chunk.clearMasks();
  chunk.setWindow(VoxelBox{BlockIndex(-6, -6, -6), BlockIndex(5, 5, 5)});
  const std::vector<BlockIndex> next = randomBlocks(10, 300);
  touch(chunk, next);
  hashed.clearMasks();
  touch(hashed, next);
  EXPECT_EQ(listing(chunk), listing(hashed));
}

}  // namespace
}  // namespace cenote::mapping
