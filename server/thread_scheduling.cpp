#include "server/thread_scheduling.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdint>

namespace cenote::server {
namespace {

// The kernel's struct sched_attr (include/uapi/linux/sched/types.h); glibc 2.36 has no wrapper.
struct SchedAttr {
  uint32_t size;
  uint32_t policy;
  uint64_t flags;
  int32_t nice;
  uint32_t priority;
  uint64_t runtime_ns;  // for SCHED_OTHER: the requested slice
  uint64_t deadline_ns;
  uint64_t period_ns;
  uint32_t util_min;
  uint32_t util_max;
};

}  // namespace

void setThreadNice(int nice) {
  if (nice != 0) setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice);
}

bool setThreadSlice(double slice_ms) {
  if (slice_ms <= 0.0) return true;
  SchedAttr attr{};
  attr.size = sizeof(attr);
  if (syscall(SYS_sched_getattr, 0, &attr, sizeof(attr), 0) != 0) return false;
  attr.size = sizeof(attr);
  attr.flags = 0;
  attr.runtime_ns = static_cast<uint64_t>(slice_ms * 1e6);
  return syscall(SYS_sched_setattr, 0, &attr, 0) == 0;
}

}  // namespace cenote::server
