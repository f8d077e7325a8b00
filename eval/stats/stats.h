// stats.h: small statistics shared by the metrics: median, summary of a set of non-negative errors,
// and a histogram with logarithmic bins for error distributions that span decades.
// Units: whatever the values are in (the metrics pass metres).
// Threads: free functions are independent; a LogHistogram belongs to one thread (merge() joins them).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/median.h"

namespace cenote::eval {

// Median of `values` (mean of the two middle values for an even count); NaN when empty.
// Reorders `values`. The one median of the project, in common/median.h.
using cenote::medianInPlace;

// Mean, median, RMSE and maximum of `values`; all NaN when empty.
struct ErrorSummary {
  size_t count = 0;
  double mean = 0.0, median = 0.0, rmse = 0.0, max = 0.0;
};
ErrorSummary summarize(std::vector<double> values);

// Counts of values in logarithmic bins between min_value and max_value (kBinsPerDecade per decade);
// values below min_value go into the first bin, values above max_value into the last.
class LogHistogram {
 public:
  static constexpr double kMinValue = 1e-5;
  static constexpr double kMaxValue = 1e3;
  static constexpr int kBinsPerDecade = 20;

  LogHistogram();
  void add(double value);
  void merge(const LogHistogram& other);

  int numBins() const { return static_cast<int>(counts_.size()); }
  // Bin i covers [edge(i), edge(i + 1)).
  static double edge(int i);
  const std::vector<int64_t>& counts() const { return counts_; }
  int64_t total() const { return total_; }

 private:
  std::vector<int64_t> counts_;
  int64_t total_ = 0;
};

}  // namespace cenote::eval
