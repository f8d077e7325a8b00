// cpu_scheduling.h: the server's time slice reaches every thread (those running before the call,
// with their own nice values kept, and those made after it), and nice values lower priority.
// The slice is read back from /proc/<pid>/task/<tid>/sched, which reports it on kernels that
// honour per-thread slices (Linux 6.12+); elsewhere the test is skipped.
#include "server/cpu/cpu_scheduling.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <optional>
#include <string>
#include <thread>

namespace cenote::server {
namespace {

// se.slice of thread `tid` in ns, if the kernel reports it.
std::optional<long> sliceNs(pid_t tid) {
  std::ifstream in("/proc/self/task/" + std::to_string(tid) + "/sched");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("se.slice", 0) == 0) return std::stol(line.substr(line.find(':') + 1));
  }
  return std::nullopt;
}

// A thread that runs until told to stop, at nice `nice`.
class Sleeper {
 public:
  explicit Sleeper(int nice)
      : thread_([this, nice] {
          setThreadNice(nice);
          tid_ = gettid();
          while (!stop_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }) {
    while (tid_ == 0) std::this_thread::yield();
  }
  ~Sleeper() {
    stop_ = true;
    thread_.join();
  }
  pid_t tid() const { return tid_; }

 private:
  std::atomic<pid_t> tid_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Nice values are relative to the process's own: the test passes run under `nice -n N` too.
TEST(CpuScheduling, NiceLowersOnlyTheCallingThread) {
  const int base = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
  ASSERT_LE(base, 12) << "run the test at nice 12 or less: 7 steps below must fit under 19";
  Sleeper background(7);
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(background.tid())), base + 7);
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(gettid())), base);
}

TEST(CpuScheduling, NiceStopsAtNineteen) {
  Sleeper background(30);
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(background.tid())), 19);
}

TEST(CpuScheduling, TimeSliceReachesEveryThreadAndKeepsTheirNice) {
  const std::optional<long> before = sliceNs(gettid());
  if (!before) GTEST_SKIP() << "this kernel does not report per-thread time slices";
  Sleeper earlier(5);
  ASSERT_TRUE(setProcessTimeSlice(0.25));
  // Whether the kernel honours requested slices (6.12+) is decided on this thread alone; then
  // every thread must have it.
  if (*sliceNs(gettid()) != 250000) GTEST_SKIP() << "this kernel ignores requested slices (before 6.12)";
  Sleeper later(0);
  for (pid_t tid : {earlier.tid(), later.tid()}) EXPECT_EQ(sliceNs(tid), std::optional<long>(250000)) << "thread " << tid;
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(earlier.tid())),
            std::min(getpriority(PRIO_PROCESS, static_cast<id_t>(gettid())) + 5, 19));
  EXPECT_TRUE(setProcessTimeSlice(0.0));  // 0: nothing changes
  EXPECT_EQ(sliceNs(gettid()), std::optional<long>(250000));
}

}  // namespace
}  // namespace cenote::server
