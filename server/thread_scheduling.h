// thread_scheduling.h: how the Linux scheduler treats the server's own threads. Background work
// (integration, the distance field) runs at a higher nice value; the gRPC handler threads ask for
// a short time slice, so that a planner's query that wakes one of them runs at once rather than
// after the slice of whatever integration thread holds the core.
// Threads: each function acts on the calling thread only (Linux priorities are per thread); threads
// it creates afterwards (an OpenMP team) inherit them.
#pragma once

namespace cenote::server {

// Lowers the calling thread's CPU priority (0 leaves it).
void setThreadNice(int nice);

// Asks for a time slice of `slice_ms` for the calling thread, keeping its policy and nice value
// (0 leaves the kernel's default, 1.4 ms on the 2-core machine). Under EEVDF (Linux 6.6+) a thread
// with a shorter slice gets an earlier deadline, and from Linux 6.12 it preempts a running thread
// with a longer slice when it wakes; older kernels accept and ignore it. The kernel clamps the
// slice to 0.1-100 ms.
// @return false when the kernel refused (no sched_setattr: the default slice stays).
bool setThreadSlice(double slice_ms);

}  // namespace cenote::server
