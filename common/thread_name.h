// thread_name.h: names the calling thread as the system shows it (/proc/PID/task/TID/comm, top -H,
// perf, gdb), so that what a thread costs can be told apart from outside the process
// (bench/viewer_bench.py sums the viewer's threads' CPU by name).
// Linux keeps 15 characters of a name; longer names are cut. Threads: any thread, for itself.
#pragma once

#include <string>

namespace cenote {

void nameThisThread(const std::string& name);

}  // namespace cenote
