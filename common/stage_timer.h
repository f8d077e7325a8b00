// stage_timer.h: per-frame durations of one pipeline stage, summarised as median and 95th
// percentile. Memory: a fixed reservoir of the most recent kMaxSamples frames, so that a long
// dive does not grow it.
// Threads: one writer (the stage's thread); read summary() after the stage has finished.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace cenote {

struct StageSummary {
  double median_ms = 0.0;
  double p95_ms = 0.0;
  double mean_ms = 0.0;
  size_t frames = 0;
};

class StageTimer {
 public:
  static constexpr size_t kMaxSamples = 4096;

  void add(double ms) {
    if (samples_.size() < kMaxSamples) {
      samples_.push_back(ms);
    } else {
      samples_[count_ % kMaxSamples] = ms;
    }
    ++count_;
    total_ms_ += ms;
  }

  StageSummary summary() const {
    StageSummary s;
    s.frames = count_;
    if (samples_.empty()) return s;
    s.median_ms = percentile(0.5);
    s.p95_ms = percentile(0.95);
    s.mean_ms = total_ms_ / static_cast<double>(count_);
    return s;
  }

  // The q-quantile (q in [0, 1]) of the recent samples, in ms; 0 without any.
  double percentile(double q) const {
    if (samples_.empty()) return 0.0;
    std::vector<double> sorted = samples_;
    const size_t k = std::min(sorted.size() - 1, static_cast<size_t>(q * static_cast<double>(sorted.size())));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
    return sorted[k];
  }
  size_t count() const { return count_; }

 private:
  std::vector<double> samples_;
  size_t count_ = 0;
  double total_ms_ = 0.0;
};

// Milliseconds since `start`.
inline double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace cenote
