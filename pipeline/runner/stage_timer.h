// stage_timer.h: per-frame durations of one pipeline stage, summarised as median and 95th
// percentile. Memory: a fixed reservoir of the most recent kMaxSamples frames, so that a long
// dive does not grow it.
// Threads: one writer (the stage's thread); read summary() after the stage has finished.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace cenote::pipeline {

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
    std::vector<double> sorted = samples_;
    std::sort(sorted.begin(), sorted.end());
    s.median_ms = sorted[sorted.size() / 2];
    s.p95_ms = sorted[std::min(sorted.size() - 1, static_cast<size_t>(0.95 * sorted.size()))];
    s.mean_ms = total_ms_ / static_cast<double>(count_);
    return s;
  }

 private:
  std::vector<double> samples_;
  size_t count_ = 0;
  double total_ms_ = 0.0;
};

// Milliseconds since `start`.
inline double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace cenote::pipeline
