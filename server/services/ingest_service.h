// ingest_service.h: Ingest (proto/cenote/v1/ingest.proto): stereo frames through the server's own
// pipeline (decode, pose, keyframes, rectify, then pipeline/runner/frame_pipeline.h: stereo and
// fusion, then the map), poses at VIO rate, and point batches. Every item is acknowledged in order;
// a bad item is rejected in its acknowledgement (status code + message) and the stream goes on:
// the map never changes for it.
// Back-pressure: a frame stream's pipeline has bounded queues; while it is full the handler stops
// reading, and gRPC's flow control slows the sender.
// Threads: any number of calls at once; each frame stream runs a pipeline (stereo and fusion
// threads) plus one thread integrating its points; at most server.max_frame_streams at a time,
// and at most server.limits.max_ingest_streams pose and point streams (each holds a gRPC thread).
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>

#include "cenote/v1/ingest.grpc.pb.h"
#include "pipeline/calibration/rectifier.h"
#include "common/stage_timer.h"
#include "server/access/call_guard.h"
#include "server/cpu/cpu_placement.h"
#include "server/host/map_host.h"
#include "server/services/pose_buffer.h"
#include "server/server_config.h"

namespace cenote::server {

// Frames counted over the server's life (Admin.GetStats).
struct IngestCounters {
  std::atomic<uint64_t> frames_received{0}, frames_processed{0}, frames_skipped{0}, frames_rejected{0};
};

struct StageSummaryNamed {
  std::string name;
  StageSummary summary;
};

// Per-frame stage durations of every frame stream: decode_rectify and integrate over all
// streams; stereo and fusion of the most recently finished stream (its pipeline's own timers).
class IngestTimings {
 public:
  void add(const std::string& stage, double ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    timers_[stage].add(ms);
  }
  void set(const std::string& stage, const StageSummary& summary) {
    std::lock_guard<std::mutex> lock(mutex_);
    finished_[stage] = summary;
  }
  std::vector<StageSummaryNamed> list() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<StageSummaryNamed> out;
    for (const auto& [name, timer] : timers_) out.push_back({name, timer.summary()});
    for (const auto& [name, summary] : finished_) out.push_back({name, summary});
    return out;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, StageTimer> timers_;
  std::map<std::string, StageSummary> finished_;
};

class IngestService final : public v1::Ingest::Service {
 public:
  // rectifier: the stereo rig; null when the server has no calibration (StreamFrames then fails
  // with FAILED_PRECONDITION). cpus: a StreamFrames call's pipeline runs on all of them, not on
  // the query CPUs its handler thread has.
  IngestService(MapHost& host, CallGuard& guard, const ServerSettings& settings,
                std::shared_ptr<const pipeline::Rectifier> rectifier, const CpuPlacement& cpus);

  grpc::Status StreamFrames(grpc::ServerContext* context,
                            grpc::ServerReaderWriter<v1::FrameAck, v1::StereoFrame>* stream) override;
  grpc::Status StreamPoses(grpc::ServerContext* context,
                           grpc::ServerReaderWriter<v1::PoseAck, v1::PoseStamped>* stream) override;
  grpc::Status StreamPoints(grpc::ServerContext* context,
                            grpc::ServerReaderWriter<v1::BatchAck, v1::PointBatch>* stream) override;
  grpc::Status IntegratePoints(grpc::ServerContext* context, const v1::PointBatch* request, v1::BatchAck* reply) override;
  grpc::Status CorrectPoses(grpc::ServerContext* context, const v1::PoseCorrection* request,
                            v1::CorrectionAck* reply) override;

  const IngestCounters& counters() const { return counters_; }
  const PoseBuffer& poses() const { return poses_; }
  std::vector<StageSummaryNamed> stageTimings() const { return timings_.list(); }

 private:
  // Validates and integrates one batch. @throws StatusError / cenote::Error; the map is unchanged then.
  void integrateBatch(const v1::PointBatch& batch, v1::BatchAck& ack);

  MapHost& host_;
  CallGuard& guard_;
  const CpuPlacement& cpus_;
  const ServerSettings& settings_;
  std::shared_ptr<const pipeline::Rectifier> rectifier_;
  PoseBuffer poses_;
  IngestCounters counters_;
  IngestTimings timings_;
  std::atomic<int> frame_streams_{0};
  std::atomic<int> ingest_streams_{0};  // StreamPoses and StreamPoints
};

}  // namespace cenote::server
