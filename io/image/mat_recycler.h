// mat_recycler.h: images whose memory is reused from frame to frame once nobody holds them.
//
// A stage that makes a new multi-MB image every frame pays for it each time: glibc hands blocks
// that large back to the kernel when they are freed, so every frame maps, zeroes and page-faults
// them in afresh. A MatRecycler keeps a reference to the images it handed out; one whose only
// reference left is its own (every cv::Mat header sharing it is gone, whichever thread dropped
// it) is handed out again for an image of the same size and type. Nothing is given back
// explicitly: the images travel through queues and windows as before.
// Threads: take() from one thread at a time; the images it returns may be used and dropped on any.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>
#include <vector>

namespace cenote::io {

class MatRecycler {
 public:
  // @param max_kept images kept at most (those in flight at once, for the memory to be reused).
  explicit MatRecycler(std::size_t max_kept) : max_kept_(max_kept) {}

  // An image of this size and type that no one else holds: a kept one when one is free, else a
  // new one (kept when there is room, or in place of a free one of another size). Its pixels are
  // whatever they were: the caller writes every one.
  cv::Mat take(int rows, int cols, int type);

 private:
  std::size_t max_kept_;
  std::vector<cv::Mat> kept_;
};

}  // namespace cenote::io
