// cpu_placement.h: which CPUs the server's threads run on. gRPC's threads (pollers and the query
// handlers that run on them) get CPUs of their own, `server.query_cpus` of them, the last of the
// CPUs the process may use; bulk work (integration, the derived structures, stereo pipelines,
// snapshots) may use every CPU, query CPUs included.
//
// Why: a planner's query is about 30 µs of server CPU, but on a busy machine it waited for a core.
// Linux wakes a thread on the CPU it last ran on, or the waker's, and does not move it to an idle
// core while the kernel thinks the cores busy; there it can wait up to a 4 ms tick behind
// integration, even behind a SCHED_IDLE thread (a thread that ran much before it slept comes back
// "ineligible" under EEVDF). Pinned, the handlers only ever wait behind each other and whatever
// bulk work the load balancer leaves on their CPU: bench/server_bench on 2 cores while ingesting at
// 15 Hz measured single-query p99 0.32-0.60 ms against 0.80-2.34 ms unpinned, with more queries
// per second (docs/PERFORMANCE.md, "Server").
// Threads: a thread inherits its creator's CPUs, so gRPC's threads are pinned by starting the
// server inside a CpuScope(kQueries); a handler starting bulk threads holds a CpuScope(kBulk).
#pragma once

#include <sched.h>

#include <string>

namespace cenote::server {

class CpuPlacement {
 public:
  // Reads the CPUs the calling thread may use (call before pinning anything). query_cpus 0, or a
  // process with no more than query_cpus CPUs: nothing is pinned.
  explicit CpuPlacement(int query_cpus);

  bool pinsQueries() const { return pins_queries_; }
  // e.g. "gRPC threads on CPU 1 of 0-1", or why nothing is pinned.
  std::string describe() const;

  // Move the calling thread (and the threads it starts from now on). Both are no-ops when
  // nothing is pinned.
  void toQueryCpus() const;
  void toAllCpus() const;

 private:
  cpu_set_t all_{};
  cpu_set_t query_{};
  bool pins_queries_ = false;
};

// Moves the calling thread to one side of a placement while it lives, and to the other after:
//  - kQueries around starting the gRPC server (its pollers inherit the query CPUs, and the threads
//    they start later do too);
//  - kBulk in a gRPC handler that does bulk work itself (a stereo frame stream): it and the
//    pipeline threads it starts run on every CPU, then it returns to the query CPUs.
class CpuScope {
 public:
  enum class Side { kQueries, kBulk };
  CpuScope(const CpuPlacement& placement, Side side) : placement_(placement), side_(side) { enter(side_); }
  ~CpuScope() { enter(side_ == Side::kQueries ? Side::kBulk : Side::kQueries); }
  CpuScope(const CpuScope&) = delete;
  CpuScope& operator=(const CpuScope&) = delete;

 private:
  void enter(Side side) const { side == Side::kQueries ? placement_.toQueryCpus() : placement_.toAllCpus(); }

  const CpuPlacement& placement_;
  const Side side_;
};

}  // namespace cenote::server
