#include "eval/stats/stats.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cenote::eval {

ErrorSummary summarize(std::vector<double> values) {
  ErrorSummary s;
  s.count = values.size();
  if (values.empty()) {
    s.mean = s.median = s.rmse = s.max = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  double sum = 0.0, sum_sq = 0.0, max = 0.0;
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
    max = std::max(max, v);
  }
  s.mean = sum / values.size();
  s.rmse = std::sqrt(sum_sq / values.size());
  s.max = max;
  s.median = medianInPlace(values);
  return s;
}

LogHistogram::LogHistogram()
    : counts_(static_cast<size_t>(std::lround(std::log10(kMaxValue / kMinValue) * kBinsPerDecade)), 0) {}

double LogHistogram::edge(int i) { return kMinValue * std::pow(10.0, static_cast<double>(i) / kBinsPerDecade); }

void LogHistogram::add(double value) {
  if (std::isnan(value)) return;
  int bin = 0;
  if (value > kMinValue) bin = static_cast<int>(std::floor(std::log10(value / kMinValue) * kBinsPerDecade));
  bin = std::clamp(bin, 0, numBins() - 1);
  ++counts_[bin];
  ++total_;
}

void LogHistogram::merge(const LogHistogram& other) {
  for (size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
  total_ += other.total_;
}

}  // namespace cenote::eval
