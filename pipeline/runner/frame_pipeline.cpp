#include "pipeline/runner/frame_pipeline.h"

#include <opencv2/imgproc.hpp>

#include "common/thread_name.h"
#include "io/image/mat_recycler.h"
#include "pipeline/fusion/back_projection.h"
#include "pipeline/fusion/fusion_window.h"
#include "pipeline/runner/team_cpu.h"
#include "pipeline/stereo/stereo_matcher.h"

namespace cenote::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

// Batches kept for reuse: the outputs in flight between fusion and the consumer, and one more.
constexpr size_t kMaxSpare = 4;
// The stereo stage's images kept for reuse (depths and converted colours): those in the depth
// queue and the fusion window at once, and a few more.
constexpr size_t kRecycledMaps = 12;

cv::Mat toBgr(const cv::Mat& image, io::MatRecycler& images) {
  if (image.channels() == 3) return image;
  cv::Mat bgr = images.take(image.rows, image.cols, CV_8UC3);
  cv::cvtColor(image, bgr, image.channels() == 4 ? cv::COLOR_BGRA2BGR : cv::COLOR_GRAY2BGR);
  return bgr;
}

}  // namespace

FramePipeline::FramePipeline(const PipelineConfig& config, bool keep_maps, std::function<void()> on_thread_start)
    : config_(config),
      keep_maps_(keep_maps),
      rectified_(config.run.queue_depth),
      depths_(config.run.queue_depth),
      outputs_(config.run.queue_depth) {
  throwIfInvalid(config_.validate(), "pipeline configuration");
  stereo_thread_ = std::thread([this, on_thread_start] {
    runStage("cenote-stereo", &FramePipeline::stereoStage, depths_, stereo_cpu_ms_, on_thread_start);
  });
  fusion_thread_ = std::thread([this, on_thread_start] {
    runStage("cenote-fusion", &FramePipeline::fusionStage, outputs_, fusion_cpu_ms_, on_thread_start);
  });
}

template <typename Output>
void FramePipeline::runStage(const char* name, void (FramePipeline::*stage)(), Output& output, double& cpu_ms,
                             const std::function<void()>& on_thread_start) {
  nameThisThread(name);
  if (on_thread_start) on_thread_start();
  try {
    (this->*stage)();
  } catch (...) {
    failure_.set(std::current_exception());
    abort();
  }
  cpu_ms = teamCpuMs();  // before close(): the owner reads it once the output has drained
  output.close();
}

FramePipeline::~FramePipeline() {
  abort();
  join();
}

bool FramePipeline::push(PosedPair frame) { return !failure_.failed() && rectified_.push(std::move(frame)); }

void FramePipeline::close() { rectified_.close(); }

std::optional<FusedOutput> FramePipeline::pop() {
  std::optional<FusedOutput> out = outputs_.pop();
  if (!out) join();
  return out;
}

void FramePipeline::recycle(PointBatch&& points) {
  std::lock_guard<std::mutex> lock(spare_mutex_);
  if (spare_.size() < kMaxSpare) spare_.push_back(std::move(points));
}

PointBatch FramePipeline::takeSpare() {
  std::lock_guard<std::mutex> lock(spare_mutex_);
  if (spare_.empty()) return {};
  PointBatch batch = std::move(spare_.back());
  spare_.pop_back();
  return batch;
}

void FramePipeline::abort() {
  rectified_.close();
  depths_.close();
  outputs_.close();
}

void FramePipeline::join() {
  if (stereo_thread_.joinable()) stereo_thread_.join();
  if (fusion_thread_.joinable()) fusion_thread_.join();
}

void FramePipeline::stereoStage() {
  StereoMatcher matcher(config_.stereo);
  // Depths and colours live on in the fusion window: their memory is reused once it drops them.
  io::MatRecycler images(kRecycledMaps);
  while (std::optional<PosedPair> item = rectified_.pop()) {
    const auto t0 = Clock::now();
    const StereoGeometry& g = item->pair.geometry;
    const DisparityMap map = matcher.match(item->pair.left, item->pair.right);
    DepthFrame frame;
    frame.t_s = item->pair.t_s;
    frame.depth = images.take(map.disparity.rows, map.disparity.cols, CV_32FC1);
    disparityToDepth(map.disparity, g.fx, g.baseline_m, frame.depth);
    frame.confidence = map.confidence;
    frame.color = toBgr(item->pair.left, images);
    frame.K = g.K();
    frame.T_world_cam = item->T_world_cam;
    ++processed_;
    stereo_timer_.add(msSince(t0));
    if (!depths_.push(std::move(frame))) break;
  }
}

void FramePipeline::fusionStage() {
  std::optional<FusionWindow> window;
  if (config_.run.fuse) window.emplace(config_.fusion);
  while (std::optional<DepthFrame> frame = depths_.pop()) {
    const auto t0 = Clock::now();
    FusedOutput out;
    if (window) {
      const FusedFrame* result = window->push(std::move(*frame));  // its maps are new: no copy
      if (!result) continue;
      out.frame.t_s = result->frame.t_s;
      out.frame.T_world_cam = result->frame.T_world_cam;
      out.frame.K = result->frame.K;
      // The window reuses its buffers at the next push: copy the maps only when they are kept.
      if (keep_maps_.load(std::memory_order_relaxed)) {
        out.frame.depth = result->frame.depth.clone();
        out.frame.confidence = result->frame.confidence.clone();
        out.frame.color = result->frame.color.clone();
      }
      // 270k points: a swap, not a copy; the window's next points go into the recycled buffers.
      out.points = takeSpare();
      window->takePoints(out.points);
    } else {
      out.points = takeSpare();
      backProject(*frame, out.points);
      out.frame = std::move(*frame);
    }
    ++fused_;
    fusion_timer_.add(msSince(t0));
    if (!outputs_.push(std::move(out))) break;
  }
}

}  // namespace cenote::pipeline
