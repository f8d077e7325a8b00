// change_feed.h: the map's changes, fanned out to subscribers (Updates.Subscribe). Each change is
// the MapDelta of one integration / clear / crop / reset with the map version after it, held once
// however many subscribers queue it. A subscriber has a queue of at most `max_lag` changes and
// `max_bytes` bytes of them (bytesOf); one that would go beyond either loses its queue and is
// told to resync (it then gets the whole map again), so a slow viewer never makes the server's
// memory grow.
// Threads: publish() from the map's writer; a Subscription is read by one thread; any thread may
// subscribe or shut the feed down. A subscription's notify callback runs on the publishing (or
// closing) thread, under the feed's lock: it must be quick and must not call the feed.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <list>
#include <memory>
#include <mutex>

#include "mapping/voxel_types.h"

namespace cenote::server {

struct MapChange {
  uint64_t version = 0;
  mapping::MapDelta delta;
};

// What a queued change holds in memory: the MapChange and its changed block indices.
size_t bytesOf(const MapChange& change);

class ChangeFeed;

class Subscription {
 public:
  enum class Next { kChange, kResync, kTimeout, kClosed };
  // Waits up to `timeout` for the next change. kResync: changes were dropped, send the whole map.
  // timeout 0: does not wait.
  Next next(MapChange& change, std::chrono::milliseconds timeout);
  // Called whenever next() would return something new (a change, a resync, the close), so that a
  // reader need not wait in next() (Updates.Subscribe's reactors, updates_service.h). Set it once,
  // before the first publish that should reach it.
  void setNotify(std::function<void()> notify);
  bool closed() const;
  // Bytes of the changes queued now (bytesOf), for the tests of the budget.
  size_t queuedBytes() const;

 private:
  friend class ChangeFeed;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::shared_ptr<const MapChange>> queue_;
  size_t queued_bytes_ = 0;
  bool resync_ = false;
  bool closed_ = false;
  std::function<void()> notify_;
};

class ChangeFeed {
 public:
  ChangeFeed(size_t max_lag, size_t max_bytes) : max_lag_(max_lag), max_bytes_(max_bytes) {}
  // The subscription stays registered while the returned pointer (or a copy) lives.
  std::shared_ptr<Subscription> subscribe();
  void unsubscribe(const std::shared_ptr<Subscription>& subscription);
  void publish(const MapChange& change);
  // Wakes every subscriber with kClosed (server shutdown).
  void close();
  size_t subscribers() const;

 private:
  const size_t max_lag_;
  const size_t max_bytes_;
  mutable std::mutex mutex_;
  std::list<std::shared_ptr<Subscription>> subscriptions_;
  bool closed_ = false;
};

}  // namespace cenote::server
