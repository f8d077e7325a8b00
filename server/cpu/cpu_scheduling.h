// cpu_scheduling.h: how the server's threads share the CPU with each other and with the rest of
// the robot's computer. Planners' short queries must not wait behind bulk work (integration,
// distance field, a large message being received):
//  - background threads run at a higher nice value (lower weight) than the query handlers;
//  - every thread of the server asks for a short time slice. Linux's EEVDF scheduler (6.6 and
//    later) lets the running thread finish its slice before a thread that wakes up gets the core;
//    with the default 0.7-3 ms slice a query waited up to that long behind integration or the
//    receiving of a 1.7 MB point batch. With 0.1 ms slices (honoured from Linux 6.12; ignored by
//    older kernels) bench/server_bench measured 15 % more queries per second while ingesting
//    and a lower p99 (docs/PERFORMANCE.md, "Server").
// Threads created afterwards inherit both settings (a thread's OpenMP team too).
#pragma once

namespace cenote::server {

// Lowers the calling thread's CPU priority by `nice` steps below the process's own (its main
// thread's) nice value, at most to 19: a server started under `nice -n 10` keeps its background
// threads below its query handlers instead of raising them to an absolute value. Linux nice
// values are per thread; 0 leaves the thread as it is.
void setThreadNice(int nice);

// Sets the time slice of every thread of the process and of those it creates later
// (0: leave the kernel's default). Returns false, changing nothing more, if the kernel refuses
// (the server then runs with the default slice).
bool setProcessTimeSlice(double slice_ms);

}  // namespace cenote::server
