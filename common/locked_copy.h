// locked_copy.h: a copy of a value read under the mutex its writers hold: what the getter of a
// member that other threads change returns, so that it never reads one half-written.
// Threads: any; the caller must not hold `mutex` already.
#pragma once

#include <mutex>

namespace cenote {

template <typename T, typename Mutex>
T lockedCopy(Mutex& mutex, const T& value) {
  std::lock_guard<Mutex> lock(mutex);
  return value;
}

}  // namespace cenote
