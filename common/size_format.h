// size_format.h: byte sizes and counts as people read them, the one formatter of the command-line
// programs, the server's logs and the benchmarks' prose.
// Bytes in binary units, as the kernel and the allocator count them: "512 B", "1.50 KiB", "11.8 MiB",
// "433 MiB", "2.00 GiB". Counts in decimal units: "950", "12.3 k", "4.56 M", "1.20 G".
// Three significant digits from 1 KiB (1 k) up; a unit is used up to 1024 (1000) of it.
// Tables with a unit in their header keep plain numbers; this is for text.
// Threads: pure functions.
#pragma once

#include <cstdint>
#include <string>

namespace cenote {

// @param bytes a size; a negative one (an unknown size) prints as "unknown".
std::string formatBytes(double bytes);

// @param count a number of things (voxels, points); a negative one prints as "unknown".
std::string formatCount(double count);

}  // namespace cenote
