#include "io/image/mat_recycler.h"

#include <atomic>

namespace cenote::io {
namespace {

// OpenCV drops references with an atomic decrement, possibly on another thread: an acquire load
// orders that thread's last reads of the image before our next writes.
bool onlyHere(const cv::Mat& m) {
  return m.u != nullptr && std::atomic_ref<int>(m.u->refcount).load(std::memory_order_acquire) == 1;
}

}  // namespace

cv::Mat MatRecycler::take(int rows, int cols, int type) {
  cv::Mat* other_shape = nullptr;  // a free image of another size or type
  for (cv::Mat& m : kept_) {
    if (!onlyHere(m)) continue;
    if (m.rows == rows && m.cols == cols && m.type() == type) return m;
    other_shape = &m;
  }
  cv::Mat image(rows, cols, type);
  if (kept_.size() < max_kept_) {
    kept_.push_back(image);
  } else if (other_shape != nullptr) {
    *other_shape = image;
  }
  return image;
}

}  // namespace cenote::io
