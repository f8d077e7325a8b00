#include "server/cpu/cpu_scheduling.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>

namespace cenote::server {

namespace {

// struct sched_attr of sched_setattr(2); glibc 2.36 has neither the struct nor a wrapper.
struct SchedAttr {
  uint32_t size;
  uint32_t policy;
  uint64_t flags;
  int32_t nice;
  uint32_t priority;
  uint64_t runtime_ns;  // for SCHED_OTHER: the requested time slice
  uint64_t deadline_ns;
  uint64_t period_ns;
  uint32_t util_min;
  uint32_t util_max;
};

constexpr uint32_t kSchedOther = 0, kSchedBatch = 3;

// Changes only the slice: sched_setattr sets policy, flags and nice too, so they are read first
// and written back (a launch tool may have made some threads real-time: those are left alone).
bool setThreadSlice(pid_t tid, uint64_t slice_ns) {
  SchedAttr attr{};
  if (syscall(SYS_sched_getattr, tid, &attr, sizeof attr, 0) != 0) return false;  // e.g. the thread ended
  if (attr.policy != kSchedOther && attr.policy != kSchedBatch) return true;
  attr.size = sizeof attr;
  attr.runtime_ns = slice_ns;
  return syscall(SYS_sched_setattr, tid, &attr, 0) == 0;
}

}  // namespace

void setThreadNice(int nice) {
  if (nice == 0) return;
  // getpriority(PRIO_PROCESS, pid) reads the main thread's nice value (its tid is the pid).
  const int base = getpriority(PRIO_PROCESS, static_cast<id_t>(getpid()));
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), std::min(base + nice, 19));
}

bool setProcessTimeSlice(double slice_ms) {
  if (slice_ms <= 0.0) return true;
  const auto slice_ns = static_cast<uint64_t>(slice_ms * 1e6);
  // The calling thread first: if the kernel refuses, no other thread is touched.
  const pid_t self = gettid();
  if (!setThreadSlice(self, slice_ns)) return false;
  std::error_code error;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", error)) {
    const pid_t tid = static_cast<pid_t>(std::stol(task.path().filename().string()));
    if (tid != self) setThreadSlice(tid, slice_ns);  // threads made before the config was read
  }
  return true;
}

}  // namespace cenote::server
