// fair_shared_mutex.h: a shared mutex that does not starve writers. glibc's rwlock (behind
// std::shared_mutex) lets new readers in while a writer waits, so readers querying back to back
// can keep integration out for ever. Here a writer first takes a turnstile that every new reader
// must pass, so it waits only for the readers already inside.
// Threads: the point of it. Meets SharedMutex: std::shared_lock / std::unique_lock work.
#pragma once

#include <mutex>
#include <shared_mutex>

namespace cenote::mapping::detail {

class FairSharedMutex {
 public:
  void lock() {
    std::lock_guard<std::mutex> turnstile(turnstile_);
    mutex_.lock();
  }
  bool try_lock() { return mutex_.try_lock(); }
  void unlock() { mutex_.unlock(); }
  void lock_shared() {
    { std::lock_guard<std::mutex> turnstile(turnstile_); }
    mutex_.lock_shared();
  }
  bool try_lock_shared() { return mutex_.try_lock_shared(); }
  void unlock_shared() { mutex_.unlock_shared(); }

 private:
  std::mutex turnstile_;
  std::shared_mutex mutex_;
};

}  // namespace cenote::mapping::detail
