// stage_failure.h: the first failure of any of a pipeline's stage threads. The other stages poll
// failed() and stop; the owner rethrows the exception once every thread has joined.
// Threads: any number.
#pragma once

#include <atomic>
#include <exception>
#include <mutex>

namespace cenote::pipeline {

class StageFailure {
 public:
  void set(std::exception_ptr e) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = e;
    failed_ = true;
  }
  bool failed() const { return failed_; }
  void rethrow() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_) std::rethrow_exception(error_);
  }

 private:
  mutable std::mutex mutex_;
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};
};

}  // namespace cenote::pipeline
