#include "pipeline/fusion/fusion_window.h"

#include <chrono>

#include "common/error.h"
#include "pipeline/fusion/back_projection.h"

namespace cenote::pipeline {

FusionWindow::FusionWindow(const FusionConfig& config) : config_(config) {
  throwIfInvalid(config_.validate(), "fusion");
  slots_.resize(config_.num_views);
  ordered_.resize(config_.num_views);
}

void FusionWindow::reset() {
  next_ = 0;
  count_ = 0;
}

const FusedFrame* FusionWindow::push(const DepthFrame& frame) {
  return pushWith(frame, [&frame](DepthFrame& slot) {
    frame.depth.copyTo(slot.depth);  // reuses the slot's buffer when the size is unchanged
    frame.confidence.copyTo(slot.confidence);
    if (frame.color.empty()) {
      slot.color.release();
    } else {
      frame.color.copyTo(slot.color);
    }
  });
}

const FusedFrame* FusionWindow::push(DepthFrame&& frame) {
  // fuseViews() takes depth and confidence of one row step (a copy has it, a view may not).
  if (frame.depth.step1() != frame.confidence.step1()) return push(static_cast<const DepthFrame&>(frame));
  return pushWith(frame, [&frame](DepthFrame& slot) {
    slot.depth = std::move(frame.depth);
    slot.confidence = std::move(frame.confidence);
    slot.color = std::move(frame.color);
  });
}

template <typename Store>
const FusedFrame* FusionWindow::pushWith(const DepthFrame& frame, Store store) {
  const cv::Size expected = count_ > 0 ? slots_[(next_ + config_.num_views - 1) % config_.num_views].depth.size()
                                       : cv::Size();
  checkFusionInput(frame, expected);

  DepthFrame& slot = slots_[next_];
  slot.t_s = frame.t_s;
  slot.K = frame.K;
  slot.T_world_cam = frame.T_world_cam;
  store(slot);
  next_ = (next_ + 1) % config_.num_views;
  count_ = std::min(count_ + 1, config_.num_views);
  if (!full()) return nullptr;

  for (int i = 0; i < config_.num_views; ++i) ordered_[i] = &slots_[(next_ + i) % config_.num_views];
  fuseViews(ordered_, config_, scratch_, result_.frame, &timings_.fusion);
  const auto start = std::chrono::steady_clock::now();
  backProject(result_.frame, result_.points);
  timings_.points_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return &result_;
}

}  // namespace cenote::pipeline
