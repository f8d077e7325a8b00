// omp_wait_policy.h: benchmarks that report CPU time run with OMP_WAIT_POLICY=passive unless the
// caller chose a policy: libgomp's idle threads otherwise spin, and the spinning counts as CPU time
// of whichever code runs then (measured: 32 vs 18 CPU ms/frame for stereo_bench's default band
// under load 5). libgomp reads the variable when it is loaded, so the process re-executes itself.
// Threads: call first thing in main(), before any thread exists.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace cenote::bench {

// Sets OMP_WAIT_POLICY=passive and re-executes `argv` when the variable is unset; on a failed
// re-execution it says so (naming `program`) and goes on with spinning waits.
inline void sleepingOpenMpWaits(char** argv, const char* program) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  setenv("OMP_WAIT_POLICY", "passive", 1);
  execv("/proc/self/exe", argv);
  std::perror((std::string(program) + ": re-executing with OMP_WAIT_POLICY=passive").c_str());
}

}  // namespace cenote::bench
