// team_cpu.h: the CPU time of a pipeline stage's thread together with its OpenMP threads. Each
// stage thread that opens parallel regions has a pool of OpenMP threads of its own (libgomp keeps
// one pool per thread that starts a region), so the calling thread and its pool is what the
// stage cost, parallel parts included. Units: milliseconds of CPU since the threads started.
// Threads: call on the stage's thread, outside any parallel region, before the thread ends (its
// pool ends with it).
#pragma once

namespace cenote::pipeline {

// The CPU time of the calling thread and of every thread of its OpenMP pool (the regions of the
// pipeline use at most omp_get_max_threads() threads, the size of the region this opens).
double teamCpuMs();

}  // namespace cenote::pipeline
