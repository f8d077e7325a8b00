#include "server/cpu/cpu_placement.h"

#include <vector>

#include "common/error.h"

namespace cenote::server {
namespace {

std::vector<int> cpusOf(const cpu_set_t& set) {
  std::vector<int> cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

// "0-3,6" style, as in /proc/<pid>/status's Cpus_allowed_list.
std::string listOf(const cpu_set_t& set) {
  const std::vector<int> cpus = cpusOf(set);
  std::string text;
  for (size_t i = 0; i < cpus.size();) {
    size_t j = i;
    while (j + 1 < cpus.size() && cpus[j + 1] == cpus[j] + 1) ++j;
    if (!text.empty()) text += ",";
    text += std::to_string(cpus[i]);
    if (j > i) text.append("-").append(std::to_string(cpus[j]));
    i = j + 1;
  }
  return text;
}

void runOn(const cpu_set_t& set) {
  // Fails only if none of the CPUs is allowed any more (a cpuset changed under us): the thread
  // then stays where it is, which is correct, only slower.
  sched_setaffinity(0, sizeof set, &set);
}

}  // namespace

CpuPlacement::CpuPlacement(int query_cpus) {
  if (sched_getaffinity(0, sizeof all_, &all_) != 0) throw Error("cannot read the CPUs this process may use");
  const std::vector<int> cpus = cpusOf(all_);
  if (query_cpus <= 0 || static_cast<int>(cpus.size()) <= query_cpus) return;
  CPU_ZERO(&query_);
  for (size_t i = cpus.size() - static_cast<size_t>(query_cpus); i < cpus.size(); ++i) CPU_SET(cpus[i], &query_);
  pins_queries_ = true;
}

std::string CpuPlacement::describe() const {
  if (!pins_queries_) return "gRPC threads not pinned (CPUs " + listOf(all_) + ")";
  return "gRPC threads on CPU " + listOf(query_) + " of " + listOf(all_);
}

void CpuPlacement::toQueryCpus() const {
  if (pins_queries_) runOn(query_);
}

void CpuPlacement::toAllCpus() const {
  if (pins_queries_) runOn(all_);
}

}  // namespace cenote::server
