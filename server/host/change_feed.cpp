#include "server/host/change_feed.h"

#include <algorithm>

namespace cenote::server {

Subscription::Next Subscription::next(MapChange& change, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  ready_.wait_for(lock, timeout, [&] { return closed_ || resync_ || !queue_.empty(); });
  if (closed_) return Next::kClosed;
  if (resync_) {
    resync_ = false;
    return Next::kResync;
  }
  if (queue_.empty()) return Next::kTimeout;
  change = std::move(queue_.front());
  queue_.pop_front();
  return Next::kChange;
}

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
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& s : subscriptions_) {
    std::lock_guard<std::mutex> sub_lock(s->mutex_);
    if (s->resync_) continue;  // it will read the whole map anyway
    if (s->queue_.size() >= max_lag_) {
      s->queue_.clear();
      s->resync_ = true;
    } else {
      s->queue_.push_back(change);
    }
    s->ready_.notify_one();
  }
}

void ChangeFeed::close() {
  std::lock_guard<std::mutex> lock(mutex_);
  closed_ = true;
  for (const auto& s : subscriptions_) {
    std::lock_guard<std::mutex> sub_lock(s->mutex_);
    s->closed_ = true;
    s->ready_.notify_all();
  }
}

size_t ChangeFeed::subscribers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return subscriptions_.size();
}

}  // namespace cenote::server
