// serial_worker.h: one thread that runs submitted jobs in order, at a CPU priority of its own. The
// map's changes all run on one such thread: a single OpenMP team marches rays (instead of one team
// per gRPC handler thread that happens to integrate), and the scheduler can favour the short
// queries of planners over ingest when the cores are busy (a higher nice value).
// Threads: run() from any thread; it blocks until the job has run and returns its result or
// rethrows its exception.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

namespace cenote::server {

class SerialWorker {
 public:
  explicit SerialWorker(int nice);
  ~SerialWorker();  // finish()

  // Runs the jobs queued so far, then ends the thread; run() afterwards throws cenote::Error.
  // Idempotent.
  void finish();
  SerialWorker(const SerialWorker&) = delete;
  SerialWorker& operator=(const SerialWorker&) = delete;

  // @throws what `job` throws, or cenote::Error "map writer stopped" after finish().
  template <typename Job>
  auto run(Job&& job) -> decltype(job()) {
    using Result = decltype(job());
    auto task = std::make_shared<std::packaged_task<Result()>>(std::forward<Job>(job));
    std::future<Result> result = task->get_future();
    submit([task] { (*task)(); });
    return result.get();
  }

 private:
  void submit(std::function<void()> job);
  void loop(int nice);

  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> jobs_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace cenote::server
