#include "server/host/change_feed.h"

#include <algorithm>

#include "common/locked_copy.h"

namespace cenote::server {

size_t bytesOf(const MapChange& change) {
  return sizeof(MapChange) + change.delta.changed_blocks.size() * sizeof(mapping::BlockIndex);
}

Subscription::Next Subscription::next(MapChange& change, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  ready_.wait_for(lock, timeout, [&] { return closed_ || resync_ || !queue_.empty(); });
  if (closed_) return Next::kClosed;
  if (resync_) {
    resync_ = false;
    return Next::kResync;
  }
  if (queue_.empty()) return Next::kTimeout;
  change = *queue_.front();
  queued_bytes_ -= bytesOf(change);
  queue_.pop_front();
  return Next::kChange;
}

void Subscription::setNotify(std::function<void()> notify) {
  std::lock_guard<std::mutex> lock(mutex_);
  notify_ = std::move(notify);
}

bool Subscription::closed() const { return lockedCopy(mutex_, closed_); }

size_t Subscription::queuedBytes() const { return lockedCopy(mutex_, queued_bytes_); }

std::shared_ptr<Subscription> ChangeFeed::subscribe() {
  auto subscription = std::make_shared<Subscription>();
  std::lock_guard<std::mutex> lock(mutex_);
  subscription->closed_ = closed_;
  subscriptions_.push_back(subscription);
  return subscription;
}

void ChangeFeed::unsubscribe(const std::shared_ptr<Subscription>& subscription) {
  std::lock_guard<std::mutex> lock(mutex_);
  subscriptions_.remove(subscription);
}

void ChangeFeed::publish(const MapChange& change) {
  const size_t bytes = bytesOf(change);
  std::shared_ptr<const MapChange> shared;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& s : subscriptions_) {
    std::function<void()> notify;
    {
      std::lock_guard<std::mutex> sub_lock(s->mutex_);
      if (s->resync_) continue;  // it will read the whole map anyway
      if (s->queue_.size() >= max_lag_ || s->queued_bytes_ + bytes > max_bytes_) {
        s->queue_.clear();
        s->queued_bytes_ = 0;
        s->resync_ = true;
      } else {
        if (!shared) shared = std::make_shared<const MapChange>(change);
        s->queue_.push_back(shared);
        s->queued_bytes_ += bytes;
      }
      s->ready_.notify_one();
      notify = s->notify_;
    }
    if (notify) notify();
  }
}

void ChangeFeed::close() {
  std::lock_guard<std::mutex> lock(mutex_);
  closed_ = true;
  for (const auto& s : subscriptions_) {
    std::function<void()> notify;
    {
      std::lock_guard<std::mutex> sub_lock(s->mutex_);
      s->closed_ = true;
      s->ready_.notify_all();
      notify = s->notify_;
    }
    if (notify) notify();
  }
}

size_t ChangeFeed::subscribers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return subscriptions_.size();
}

}  // namespace cenote::server
