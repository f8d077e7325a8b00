// SerialWorker: the one thread that runs the map's changes, in order.
#include "server/host/serial_worker.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/error.h"

namespace cenote::server {
namespace {

TEST(SerialWorker, RunsJobsInOrderAndRefusesJobsAfterFinish) {
  SerialWorker worker(0);
  std::vector<int> order;
  for (int i = 0; i < 3; ++i) worker.run([&] { order.push_back(i); });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2}));
  EXPECT_THROW(worker.run([] { throw Error("bad batch"); }), Error);  // a job's error reaches its caller
  worker.finish();
  try {
    worker.run([] { return 1; });
    ADD_FAILURE() << "run() after finish() returned";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("map writer stopped"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cenote::server
