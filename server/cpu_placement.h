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
// 15 Hz measured single-query p99 0.3-0.56 ms against 0.6-1.4 ms unpinned, at the same queries per
// second (docs/PERFORMANCE.md, "Server").
// Threads: a thread inherits its creator's CPUs, so gRPC's threads are pinned by starting the
// server inside a QueryCpuScope; a bulk thread started from a handler calls toAllCpus() first.
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

// The calling thread runs on the query CPUs while it lives (and threads it starts then stay there).
class QueryCpuScope {
 public:
  explicit QueryCpuScope(const CpuPlacement& placement) : placement_(placement) { placement_.toQueryCpus(); }
  ~QueryCpuScope() { placement_.toAllCpus(); }
  QueryCpuScope(const QueryCpuScope&) = delete;
  QueryCpuScope& operator=(const QueryCpuScope&) = delete;

 private:
  const CpuPlacement& placement_;
};

// The opposite, for a gRPC handler that does bulk work itself (a stereo frame stream): it runs on
// every CPU while this lives, and returns to the query CPUs after.
class BulkCpuScope {
 public:
  explicit BulkCpuScope(const CpuPlacement& placement) : placement_(placement) { placement_.toAllCpus(); }
  ~BulkCpuScope() { placement_.toQueryCpus(); }
  BulkCpuScope(const BulkCpuScope&) = delete;
  BulkCpuScope& operator=(const BulkCpuScope&) = delete;

 private:
  const CpuPlacement& placement_;
};

}  // namespace cenote::server
