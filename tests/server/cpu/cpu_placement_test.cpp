// cpu_placement.h: gRPC's threads go to the last `query_cpus` CPUs of the process, threads they
// start stay there, and bulk work (CpuScope kBulk) and everything else keep every CPU. Needs a
// process allowed at least 2 CPUs; skipped otherwise.
#include "server/cpu/cpu_placement.h"

#include <gtest/gtest.h>
#include <sched.h>

#include <thread>
#include <vector>

namespace cenote::server {
namespace {

std::vector<int> cpusOfThisThread() {
  cpu_set_t set;
  CPU_ZERO(&set);
  sched_getaffinity(0, sizeof set, &set);
  std::vector<int> cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

std::vector<int> cpusOfNewThread() {
  std::vector<int> cpus;
  std::thread([&] { cpus = cpusOfThisThread(); }).join();
  return cpus;
}

TEST(CpuPlacement, QueryThreadsAndTheirThreadsRunOnTheLastCpus) {
  const std::vector<int> all = cpusOfThisThread();
  if (all.size() < 2) GTEST_SKIP() << "the process may use only " << all.size() << " CPU";
  const CpuPlacement placement(1);
  ASSERT_TRUE(placement.pinsQueries());
  {
    CpuScope pinned(placement, CpuScope::Side::kQueries);
    EXPECT_EQ(cpusOfThisThread(), std::vector<int>{all.back()});
    EXPECT_EQ(cpusOfNewThread(), std::vector<int>{all.back()});  // gRPC's later pollers
    {
      CpuScope bulk(placement, CpuScope::Side::kBulk);  // a frame stream's handler
      EXPECT_EQ(cpusOfThisThread(), all);
      EXPECT_EQ(cpusOfNewThread(), all);  // its pipeline threads
    }
    EXPECT_EQ(cpusOfThisThread(), std::vector<int>{all.back()});
  }
  EXPECT_EQ(cpusOfThisThread(), all);
  EXPECT_EQ(cpusOfNewThread(), all);
}

TEST(CpuPlacement, DescribeNamesTheCpus) {
  const std::vector<int> all = cpusOfThisThread();
  if (all.size() != 2) GTEST_SKIP() << "the expected text is written for 2 CPUs";
  const std::string pair = std::to_string(all[0]) + (all[1] == all[0] + 1 ? "-" : ",") + std::to_string(all[1]);
  EXPECT_EQ(CpuPlacement(1).describe(), "gRPC threads on CPU " + std::to_string(all[1]) + " of " + pair);
  EXPECT_EQ(CpuPlacement(0).describe(), "gRPC threads not pinned (CPUs " + pair + ")");
}

TEST(CpuPlacement, NothingIsPinnedWithoutACpuLeftForBulkWork) {
  const std::vector<int> all = cpusOfThisThread();
  for (int query_cpus : {0, static_cast<int>(all.size()), static_cast<int>(all.size()) + 3}) {
    const CpuPlacement placement(query_cpus);
    EXPECT_FALSE(placement.pinsQueries()) << query_cpus;
    CpuScope pinned(placement, CpuScope::Side::kQueries);
    EXPECT_EQ(cpusOfThisThread(), all) << query_cpus;
  }
}

}  // namespace
}  // namespace cenote::server
