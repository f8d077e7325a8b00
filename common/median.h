// median.h: the median of a sample (timings of benchmarks and commands, errors of the metrics).
// Even sizes give the mean of the two middle values; an empty sample gives NaN.
// Threads: pure functions.
#pragma once

#include <vector>

namespace cenote {

// Reorders `values` (std::nth_element): O(n).
double medianInPlace(std::vector<double>& values);
// The same on a copy.
inline double median(std::vector<double> values) { return medianInPlace(values); }

}  // namespace cenote
