#include "common/cpu_clock.h"

#include <ctime>

namespace cenote {
namespace {

double clockMs(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace

double threadCpuMs() { return clockMs(CLOCK_THREAD_CPUTIME_ID); }

double processCpuMs() { return clockMs(CLOCK_PROCESS_CPUTIME_ID); }

}  // namespace cenote
