#include "server/host/serial_worker.h"

#include "common/error.h"
#include "server/cpu/cpu_scheduling.h"

namespace cenote::server {

SerialWorker::SerialWorker(int nice) : thread_([this, nice] { loop(nice); }) {}

SerialWorker::~SerialWorker() { finish(); }

void SerialWorker::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  ready_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void SerialWorker::submit(std::function<void()> job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // A late call during shutdown: no thread would ever run it, and its caller would wait for ever.
    if (stop_) throw Error("map writer stopped: the server is shutting down");
    jobs_.push_back(std::move(job));
  }
  ready_.notify_one();
}

void SerialWorker::loop(int nice) {
  setThreadNice(nice);
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    ready_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
    if (jobs_.empty()) return;  // stopping, nothing left
    std::function<void()> job = std::move(jobs_.front());
    jobs_.pop_front();
    lock.unlock();
    job();  // a packaged_task: its exception goes to the caller's future
    lock.lock();
  }
}

}  // namespace cenote::server
