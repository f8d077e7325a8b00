// change_feed.h: the map's changes, fanned out to subscribers (Updates.Subscribe). Each change is
// the MapDelta of one integration / clear / crop / reset with the map version after it. A
// subscriber has a queue of at most `max_lag` changes; one that falls further behind loses its
// queue and is told to resync (it then gets the whole map again), so a slow viewer never makes
// the server's memory grow.
// Threads: publish() from the map's writer; a Subscription is read by one thread; any thread may
// subscribe or shut the feed down.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <list>
#include <memory>
#include <mutex>

#include "mapping/voxel_types.h"

namespace cenote::server {

struct MapChange {
  uint64_t version = 0;
  mapping::MapDelta delta;
};

class ChangeFeed;

class Subscription {
 public:
  enum class Next { kChange, kResync, kTimeout, kClosed };
  // Waits up to `timeout` for the next change. kResync: changes were dropped, send the whole map.
  Next next(MapChange& change, std::chrono::milliseconds timeout);

 private:
  friend class ChangeFeed;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<MapChange> queue_;
  bool resync_ = false;
  bool closed_ = false;
};

class ChangeFeed {
 public:
  explicit ChangeFeed(size_t max_lag) : max_lag_(max_lag) {}
  // The subscription stays registered while the returned pointer (or a copy) lives.
  std::shared_ptr<Subscription> subscribe();
  void unsubscribe(const std::shared_ptr<Subscription>& subscription);
  void publish(const MapChange& change);
  // Wakes every subscriber with kClosed (server shutdown).
  void close();
  size_t subscribers() const;

 private:
  const size_t max_lag_;
  mutable std::mutex mutex_;
  std::list<std::shared_ptr<Subscription>> subscriptions_;
  bool closed_ = false;
};

}  // namespace cenote::server
