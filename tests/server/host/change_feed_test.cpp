// The change feed's bounds: a subscriber's queue holds at most max_lag changes and max_bytes bytes
// of them (bytesOf); beyond either it is emptied and the subscriber told to resync. Its notify
// callback runs for every change, resync and close, so a reader need not wait in next().
#include "server/host/change_feed.h"

#include <gtest/gtest.h>

namespace cenote::server {
namespace {

MapChange changeOf(uint64_t version, int blocks) {
  MapChange change;
  change.version = version;
  for (int i = 0; i < blocks; ++i) change.delta.changed_blocks.push_back(mapping::BlockIndex(i, 0, 0));
  return change;
}

TEST(ChangeFeed, BytesOfAChangeAreItsBlockIndicesAndItsHeader) {
  EXPECT_EQ(bytesOf(changeOf(1, 0)), sizeof(MapChange));
  EXPECT_EQ(bytesOf(changeOf(1, 100)), sizeof(MapChange) + 100 * sizeof(mapping::BlockIndex));
}

TEST(ChangeFeed, ASubscriberBeyondItsByteBudgetIsResyncedThoughUnderItsCount) {
  const size_t one = bytesOf(changeOf(0, 100));
  ChangeFeed feed(64, 3 * one);  // room for 3 changes of 100 blocks, far below 64 changes
  const auto s = feed.subscribe();
  for (uint64_t v = 1; v <= 3; ++v) feed.publish(changeOf(v, 100));
  EXPECT_EQ(s->queuedBytes(), 3 * one);
  feed.publish(changeOf(4, 100));  // a fourth would need 4 * one bytes
  EXPECT_EQ(s->queuedBytes(), 0u);
  MapChange change;
  EXPECT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kResync);
  EXPECT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kTimeout);
  // After the resync it queues again, and reads them in order.
  feed.publish(changeOf(5, 100));
  feed.publish(changeOf(6, 10));
  EXPECT_EQ(s->queuedBytes(), one + bytesOf(changeOf(0, 10)));
  ASSERT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kChange);
  EXPECT_EQ(change.version, 5u);
  EXPECT_EQ(change.delta.changed_blocks.size(), 100u);
  ASSERT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kChange);
  EXPECT_EQ(change.version, 6u);
  EXPECT_EQ(s->queuedBytes(), 0u);
}

TEST(ChangeFeed, ASubscriberBeyondItsCountIsResyncedThoughUnderItsBytes) {
  ChangeFeed feed(2, 1 << 30);
  const auto s = feed.subscribe();
  for (uint64_t v = 1; v <= 3; ++v) feed.publish(changeOf(v, 1));
  MapChange change;
  EXPECT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kResync);
}

TEST(ChangeFeed, OneChangeLargerThanTheBudgetIsAResync) {
  ChangeFeed feed(64, bytesOf(changeOf(0, 10)));
  const auto s = feed.subscribe();
  feed.publish(changeOf(1, 11));
  MapChange change;
  EXPECT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kResync);
}

TEST(ChangeFeed, NotifyRunsForEveryChangeResyncAndClose) {
  ChangeFeed feed(1, 1 << 30);
  const auto s = feed.subscribe();
  int notified = 0;
  s->setNotify([&] { ++notified; });
  feed.publish(changeOf(1, 1));
  EXPECT_EQ(notified, 1);
  feed.publish(changeOf(2, 1));  // over the count: a resync, notified too
  EXPECT_EQ(notified, 2);
  feed.publish(changeOf(3, 1));  // already to be resynced: nothing new to tell
  EXPECT_EQ(notified, 2);
  EXPECT_FALSE(s->closed());
  feed.close();
  EXPECT_EQ(notified, 3);
  EXPECT_TRUE(s->closed());
  MapChange change;
  EXPECT_EQ(s->next(change, std::chrono::milliseconds(0)), Subscription::Next::kClosed);
  EXPECT_EQ(feed.subscribers(), 1u);
  feed.unsubscribe(s);
  EXPECT_EQ(feed.subscribers(), 0u);
}

}  // namespace
}  // namespace cenote::server
