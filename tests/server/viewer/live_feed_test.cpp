// live_feed_test.cpp: the viewer's live feed holds the newest camera images, made only when a
// viewer wants them and no more often than image_hz.
#include "server/viewer/live_feed.h"

#include <gtest/gtest.h>

namespace cenote::server::viewer {
namespace {

TEST(LiveFeedImages, AreDueOnlyWhileWantedAndImagesAreOn) {
  LiveFeed feed(100, 10, 2.0);
  EXPECT_FALSE(feed.imagesDue());  // nobody wants them
  feed.setWanted(false, true);
  EXPECT_TRUE(feed.imagesDue());
  feed.setWanted(false, false);
  EXPECT_FALSE(feed.imagesDue());

  LiveFeed off(100, 10, 0.0);
  off.setWanted(false, true);
  EXPECT_FALSE(off.imagesDue());
}

TEST(LiveFeedImages, APostHoldsTheNewestPairAndWaitsOnePeriod) {
  LiveFeed feed(100, 10, 1.0e-3);  // one pair per 1000 s
  feed.setWanted(false, true);
  EXPECT_EQ(feed.images().version, 0u);
  EXPECT_EQ(feed.images().left_jpeg, nullptr);
  feed.postImages(1.5, "left", "disparity");
  EXPECT_FALSE(feed.imagesDue());
  const LiveFeed::Images images = feed.images();
  EXPECT_EQ(images.version, 1u);
  EXPECT_EQ(images.t_s, 1.5);
  EXPECT_EQ(*images.left_jpeg, "left");
  EXPECT_EQ(*images.disparity_jpeg, "disparity");
  feed.postImages(2.5, "left 2", "disparity 2");  // a poster that did not ask: still the newest
  EXPECT_EQ(feed.images().version, 2u);
  EXPECT_EQ(*feed.images().left_jpeg, "left 2");
}

}  // namespace
}  // namespace cenote::server::viewer
