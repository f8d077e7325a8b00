// frame_pipeline.h: the stereo and fusion stages for rectified, posed frames pushed one at a time.
//
//   push() ──► stereo ──► fusion ──► pop()
//
// Each stage runs on its own thread with bounded queues between them (run.queue_depth frames), so
// push() blocks while the stages are behind: back-pressure instead of unbounded memory. Both the
// Runner (frames read from a recorded dataset) and the gRPC server (frames received from a
// vehicle) feed it, both through pipeline/frame/frame_admission.h, so the same frames in the same order give the same points, bit for bit.
// Units and frames: those of DepthFrame and PointBatch (metres, seconds, world frame).
// Threads: push()/close() from one producer thread, pop() from one consumer thread; stereo and
// fusion use OpenMP inside and are deterministic for any thread count.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "common/point_batch.h"
#include "pipeline/frame/frames.h"
#include "pipeline/runner/bounded_queue.h"
#include "pipeline/runner/run_config.h"
#include "pipeline/runner/stage_failure.h"
#include "common/stage_timer.h"

namespace cenote::pipeline {

// What comes out for every fused reference frame (or every frame, without fusion).
struct FusedOutput {
  DepthFrame frame;   // t_s, K and T_world_cam always; depth, confidence and colour only while maps are kept
  PointBatch points;  // world frame, origin = the reference camera's centre
};

class FramePipeline {
 public:
  // Starts the stage threads. keep_maps: outputs carry the fused depth maps (to write them out).
  // on_thread_start: runs first on each stage thread (the server lowers their CPU priority with it).
  // @throws cenote::Error for an invalid stereo or fusion setting.
  FramePipeline(const PipelineConfig& config, bool keep_maps, std::function<void()> on_thread_start = {});
  // Closes the input and joins the threads (frames in flight are finished and dropped).
  ~FramePipeline();
  FramePipeline(const FramePipeline&) = delete;
  FramePipeline& operator=(const FramePipeline&) = delete;

  // Whether the outputs made from now on carry the fused maps (any thread; the server keeps them
  // only while a viewer wants the camera images, host_viewer.h).
  void setKeepMaps(bool keep) { keep_maps_.store(keep, std::memory_order_relaxed); }
  // Blocks while the stereo queue is full. @return false once the pipeline failed or was closed.
  bool push(PosedPair frame);
  // No more input: pop() drains the frames in flight, then reports the end.
  void close();
  // Blocks until the next output. @return nullopt once closed and drained, or after a failure.
  std::optional<FusedOutput> pop();
  // Hands back the points of a popped output once they are used (any thread): a later output's
  // points are written into their buffers instead of new ones (a frame's 4 MB, page-faulted in
  // afresh each time). Optional; at most a few batches are kept.
  void recycle(PointBatch&& points);
  // Stops every stage now (after a failure elsewhere); pending frames are dropped.
  void abort();
  // Rethrows the first exception of a stage thread, if any (call after pop() returned nullopt).
  void rethrowIfFailed() const { failure_.rethrow(); }
  bool failed() const { return failure_.failed(); }

  size_t framesProcessed() const { return processed_; }  // through stereo
  size_t framesFused() const { return fused_; }          // outputs produced
  // Per-frame durations; read once the pipeline has drained.
  StageSummary stereoTiming() const { return stereo_timer_.summary(); }
  StageSummary fusionTiming() const { return fusion_timer_.summary(); }
  // CPU time of each stage's thread and its OpenMP threads over the whole run, in ms (team_cpu.h);
  // read once the pipeline has drained.
  double stereoCpuMs() const { return stereo_cpu_ms_; }
  double fusionCpuMs() const { return fusion_cpu_ms_; }

 private:
  void stereoStage();
  void fusionStage();
  // Runs `stage` on this thread, named `name` (thread_name.h): its first exception is kept
  // (rethrowIfFailed) and stops every stage; its CPU time goes to `cpu_ms`; the stage's `output`
  // is closed either way, which ends the next stage.
  template <typename Output>
  void runStage(const char* name, void (FramePipeline::*stage)(), Output& output, double& cpu_ms,
                const std::function<void()>& on_thread_start);
  void join();
  // A recycled batch (its buffers kept), or an empty one.
  PointBatch takeSpare();

  const PipelineConfig config_;
  std::atomic<bool> keep_maps_;
  BoundedQueue<PosedPair> rectified_;
  BoundedQueue<DepthFrame> depths_;
  BoundedQueue<FusedOutput> outputs_;
  StageFailure failure_;
  StageTimer stereo_timer_, fusion_timer_;
  double stereo_cpu_ms_ = 0.0, fusion_cpu_ms_ = 0.0;  // written by the stage threads before they close
  std::atomic<size_t> processed_{0}, fused_{0};
  std::mutex spare_mutex_;
  std::vector<PointBatch> spare_;  // recycled batches, at most kMaxSpare
  std::thread stereo_thread_, fusion_thread_;
};

}  // namespace cenote::pipeline
