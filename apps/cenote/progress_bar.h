// progress_bar.h: progress of a long job on the terminal: a bar with frames, rate and time left
// when stderr is a terminal, a plain line every tenth of the job otherwise (logs, CI).
// Threads: one thread calls update().
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace cenote::apps {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label) : label_(std::move(label)), tty_(isatty(STDERR_FILENO) != 0) {}

  void update(size_t done, size_t total) {
    if (finished_) return;
    finished_ = done == total;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double rate = elapsed > 0.0 ? done / elapsed : 0.0;
    const double eta = rate > 0.0 ? (total - done) / rate : 0.0;
    if (tty_) {
      constexpr int kWidth = 30;
      const int filled = total ? static_cast<int>(kWidth * done / total) : kWidth;
      std::fprintf(stderr, "\r%s [%s%s] %zu/%zu frames  %.1f fps  ETA %.0f s ", label_.c_str(),
                   std::string(filled, '#').c_str(), std::string(kWidth - filled, ' ').c_str(), done, total, rate, eta);
      if (done == total) std::fprintf(stderr, "\n");
    } else {
      const size_t step = total >= 10 ? total / 10 : 1;
      if (done == total || done >= last_printed_ + step) {
        std::fprintf(stderr, "%s: %zu/%zu frames, %.1f fps\n", label_.c_str(), done, total, rate);
        last_printed_ = done;
      }
    }
  }

 private:
  std::string label_;
  bool tty_;
  size_t last_printed_ = 0;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace cenote::apps
