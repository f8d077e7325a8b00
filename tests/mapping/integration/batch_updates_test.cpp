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

// A build of `blocks` into `updates` through the window `window`, and its listing.
std::vector<std::string> buildInWindow(BatchUpdates& updates, const VoxelBox& window,
                                       const std::vector<BlockIndex>& blocks) {
  updates.clearMasks();
  updates.setWindow(window);
  touch(updates, blocks);
  return listing(updates);
}

// The listing of the same build through the hash table alone.
std::vector<std::string> buildHashed(const std::vector<BlockIndex>& blocks) {
  BatchUpdates updates;
  updates.clearMasks();
  touch(updates, blocks);
  return listing(updates);
}

const VoxelBox kAll{BlockIndex(-6, -6, -6), BlockIndex(5, 5, 5)};

TEST(BatchUpdates, WindowFindsTheSameBlocksAsTheHashTable) {
  const VoxelBox part{BlockIndex(-2, -3, -1), BlockIndex(3, 2, 4)};  // blocks outside it too
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const std::vector<BlockIndex> blocks = randomBlocks(seed, 3000);
    BatchUpdates windowed;
    EXPECT_EQ(buildInWindow(windowed, part, blocks), buildHashed(blocks)) << "seed " << seed;
  }
}

TEST(BatchUpdates, WindowForgetsItsBlocksBetweenBuilds) {
  // The second build reuses the window's memory with another box: a cell left from the first
  // build would hand out a slot of a block that this build does not hold.
  BatchUpdates windowed;
  buildInWindow(windowed, kAll, randomBlocks(7, 2000));
  const std::vector<BlockIndex> second = randomBlocks(8, 500);
  EXPECT_EQ(buildInWindow(windowed, VoxelBox{BlockIndex(-4, -5, -6), BlockIndex(5, 3, 2)}, second), buildHashed(second));
}

TEST(BatchUpdates, SwappedMasksLeaveNoWindowBehind) {
  // RayBatch takes chunk 0's masks over with swapMasks: the chunk's next build must not find the
  // blocks it handed over.
  BatchUpdates chunk, result;
  chunk.clearMasks();
  chunk.setWindow(kAll);
  touch(chunk, randomBlocks(9, 1000));
  result.swapMasks(chunk);
  const std::vector<BlockIndex> next = randomBlocks(10, 300);
  EXPECT_EQ(buildInWindow(chunk, kAll, next), buildHashed(next));
}

}  // namespace
}  // namespace cenote::mapping
