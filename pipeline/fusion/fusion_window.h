// fusion_window.h: the sliding window of depth frames that feeds depth-map fusion.
// Keeps the last N_f frames (copies, or the frames themselves when moved in); once full, every push() fuses the window into its middle
// (reference) frame with fuseViews() (rules in depth_fusion.h) and back-projects the result into
// coloured world points. The oldest frame leaves as each new one arrives, so memory and latency
// are constant: frame buffers, z-buffers, the fused maps and the point batch are allocated while
// the window fills and reused after that (as long as the image size stays the same).
// Units and frames: those of DepthFrame (metres, T_world_cam) and PointBatch (world frame).
// Threads: push() uses OpenMP inside and is deterministic for any thread count; one FusionWindow
// must not be used from two threads at once.
#pragma once

#include <utility>
#include <vector>

#include "common/point_batch.h"
#include "pipeline/fusion/depth_fusion.h"
#include "pipeline/fusion/fusion_config.h"

namespace cenote::pipeline {

// The fused reference frame and its points.
struct FusedFrame {
  DepthFrame frame;   // fused depth (+inf where rejected) and confidence (0 where rejected);
                      // t_s, K, T_world_cam and color of the reference view
  PointBatch points;  // one point per fused pixel, world frame, RGB colours when the frame has colour
};

struct FusionWindowTimings {
  FusionTimings fusion;    // rendering and fusion
  double points_ms = 0.0;  // back-projection into the point batch
};

class FusionWindow {
 public:
  // @throws cenote::Error listing every invalid setting.
  explicit FusionWindow(const FusionConfig& config);

  // Copies `frame` into the window (dropping the oldest when full). When the window then holds
  // N_f frames, fuses them.
  // @return the fused reference frame, or nullptr while the window is still filling.
  // @warning the returned frame, its Mats (which share memory with the window) and its points are
  //          overwritten by the next push(); clone what you keep.
  // @throws cenote::Error when the frame cannot take part (depth / confidence not CV_32FC1 of one
  //         size, colour not CV_8UC3 of that size, non-pinhole K, non-finite or non-orthonormal
  //         pose) or its size differs from the frames already in the window. The window is then
  //         unchanged.
  const FusedFrame* push(const DepthFrame& frame);
  // The same, taking the frame's Mats into the window instead of copying their pixels (the
  // pipeline's stereo stage makes new maps for every frame): the caller must not write to those
  // pixels afterwards. On an error the frame is left as it was.
  const FusedFrame* push(DepthFrame&& frame);

  // Hands the last fused frame's points to `out` without copying them (their buffers are
  // swapped: the window's points are then out's old ones, overwritten by the next push()).
  void takePoints(PointBatch& out) { std::swap(out, result_.points); }

  // Empties the window (buffers are kept); the next frames may have another size.
  void reset();

  int size() const { return count_; }
  bool full() const { return count_ == config_.num_views; }
  const FusionConfig& config() const { return config_; }
  const FusionWindowTimings& lastTimings() const { return timings_; }

 private:
  // Checks `frame` against the window, then stores it in the next slot with `store(slot)`.
  template <typename Store>
  const FusedFrame* pushWith(const DepthFrame& frame, Store store);

  FusionConfig config_;
  std::vector<DepthFrame> slots_;           // ring buffer of N_f frames
  std::vector<const DepthFrame*> ordered_;  // the slots, oldest first
  int next_ = 0;                            // slot the next frame goes to
  int count_ = 0;                           // frames in the window
  FusionScratch scratch_;
  FusedFrame result_;
  FusionWindowTimings timings_;
};

}  // namespace cenote::pipeline
