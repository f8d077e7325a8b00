// cpu_clock.h: CPU time spent, as opposed to wall time, for telling what a stage of a pipeline
// costs when stages overlap on few cores (their wall medians then include the time they waited
// for the CPU). Units: milliseconds of CPU (user + system).
// Threads: any thread; each call reads the kernel's clocks and shares no state.
#pragma once

namespace cenote {

// CPU time of the calling thread since it started (CLOCK_THREAD_CPUTIME_ID).
double threadCpuMs();
// CPU time of the whole process, every thread, since it started (CLOCK_PROCESS_CPUTIME_ID).
double processCpuMs();

}  // namespace cenote
