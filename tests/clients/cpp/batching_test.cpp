// Batching: how the client splits long requests and point batches into calls.
#include "clients/cpp/batching.h"

#include <gtest/gtest.h>

#include "tests/clients/cpp/wall_scene.h"

namespace cenote::client::test {
namespace {

TEST(Batching, RangesCoverEveryItemOnceInOrder) {
  EXPECT_TRUE(batchRanges(0, 10).empty());
  const auto ranges = batchRanges(25, 10);
  ASSERT_EQ(ranges.size(), 3u);
  EXPECT_EQ(ranges[0], std::make_pair(size_t{0}, size_t{10}));
  EXPECT_EQ(ranges[2], std::make_pair(size_t{20}, size_t{25}));
  EXPECT_EQ(batchRanges(25, 0).size(), 1u);
  PointBatch batch = wallBatch();
  batch.rgb.assign(batch.size(), {1, 2, 3});
  const auto parts = splitPointBatch(batch, 500);
  ASSERT_EQ(parts.size(), 4u);
  EXPECT_EQ(parts[3].size(), 100u);
  EXPECT_EQ(parts[3].rgb.size(), 100u);
  EXPECT_EQ(parts[1].points_m.front(), batch.points_m[500]);
  EXPECT_EQ(parts[2].origin_m, batch.origin_m);
}

}  // namespace
}  // namespace cenote::client::test
