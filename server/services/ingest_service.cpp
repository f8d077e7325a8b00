#include "server/services/ingest_service.h"

#include <cmath>
#include <iostream>
#include <thread>

#include "pipeline/runner/frame_pipeline.h"
#include "pipeline/frame/frame_admission.h"
#include "server/cpu/cpu_scheduling.h"
#include "server/viewer/host_viewer.h"
#include "server/wire/frame_decoder.h"
#include "server/wire/wire.h"

namespace cenote::server {
namespace {

using Clock = std::chrono::steady_clock;

// Holds one of the server's stream slots of a kind for the life of a call: each such stream holds
// a thread of gRPC's sync server, and the rest must stay for the planners' queries.
class StreamSlot {
 public:
  // what: "frame streams"; limit: the key, "server.max_frame_streams".
  StreamSlot(std::atomic<int>& active, int max, const char* what, const char* limit) : active_(active) {
    if (++active_ > max) {
      --active_;
      throw resourceExhausted("already " + std::to_string(max) + " " + what + " running: the limit " + limit);
    }
  }
  ~StreamSlot() { --active_; }

 private:
  std::atomic<int>& active_;
};

// Reads every item of a bidirectional stream and writes its acknowledgement, numbered from 0, in
// order. handle(item, ack) fills the ack; false ends the stream after writing it.
template <typename Ack, typename Item, typename Handle>
void acknowledgeEach(grpc::ServerReaderWriter<Ack, Item>* stream, Handle&& handle) {
  Item item;
  for (uint64_t sequence = 0; stream->Read(&item); ++sequence) {
    Ack ack;
    ack.set_sequence(sequence);
    const bool go_on = handle(item, ack);
    stream->Write(ack);
    if (!go_on) break;
  }
}

template <typename Ack>
void reject(Ack& ack, const StatusError& e) {
  ack.set_status_code(static_cast<int32_t>(e.code()));
  ack.set_message(e.what());
}

// A pose or point stream: holds one of the `max` slots of such streams (server.limits.max_ingest_streams)
// for the call and acknowledges each item. An item for which handle(item, ack) throws (StatusError,
// cenote::Error) is rejected in its ack, and the stream goes on.
template <typename Ack, typename Item, typename Handle>
grpc::Status acknowledgeIngest(std::atomic<int>& active, int max, grpc::ServerReaderWriter<Ack, Item>* stream,
                               Handle&& handle) {
  StreamSlot slot(active, max, "pose and point streams", "server.limits.max_ingest_streams");
  acknowledgeEach(stream, [&](const Item& item, Ack& ack) {
    try {
      handle(item, ack);
    } catch (const StatusError& e) {
      reject(ack, e);
    } catch (const Error& e) {
      reject(ack, toStatusError(e));
    }
    return true;
  });
  return grpc::Status::OK;
}

// One StreamFrames call: its pipeline, the thread that integrates what comes out, its keyframes.
class FrameStream {
 public:
  FrameStream(MapHost& host, const ServerSettings& settings, const pipeline::Rectifier& rectifier, PoseBuffer& poses,
              IngestCounters& counters, IngestTimings& timings)
      : host_(host),
        settings_(settings),
        T_raw_rect_(pipeline::rectifiedFromRaw(rectifier)),
        baseline_m_(rectifier.geometry().baseline_m),
        admission_(rectifier, settings.pipeline.run),
        limits_{settings.server.limits.max_image_pixels, rectifier.geometry().image_size},
        poses_(poses),
        counters_(counters),
        timings_(timings),
        // Stereo, fusion and handing their points to the map run below the query handlers' CPU
        // priority, as integration does (cpu_scheduling.h).
        stages_(settings.pipeline, false, [nice = settings.server.host.ingest_nice] { setThreadNice(nice); }),
        integrator_([this] {
          setThreadNice(settings_.server.host.ingest_nice);
          integrateOutputs();
        }) {}

  ~FrameStream() {
    stages_.abort();
    if (integrator_.joinable()) integrator_.join();
  }

  // Runs one frame up to the pipeline's input (pipeline/frame/frame_admission.h decides, as it
  // does for `cenote run`). Fills the ack; false when the pipeline has failed. Whatever fails
  // inside one frame (its decoding, rectification, an exception of OpenCV's) rejects that frame
  // alone: the stream and the frames already in the pipeline go on.
  bool handle(const v1::StereoFrame& wire, v1::FrameAck& ack) {
    ack.set_timestamp_s(wire.timestamp_s());
    ++counters_.frames_received;
    try {
      const double previous_t_s = admission_.lastTimestamp();
      poses_.noteFrameTime(wire.timestamp_s());
      const pipeline::FrameDecision decision = admission_.decide(wire.timestamp_s(),
                                                                 [&](double t_s) { return poseOf(wire, t_s); });
      switch (decision.admission) {
        case pipeline::Admission::kOutOfOrder:
          throw invalidArgument("timestamp_s = " + std::to_string(wire.timestamp_s()) +
                                " is not after the previous frame's (" + std::to_string(previous_t_s) +
                                "): frames must come in time order");
        case pipeline::Admission::kNoPose:
          skip(ack, v1::FRAME_OUTCOME_SKIPPED_NO_POSE,
               "no pose of its own and no two streamed poses bracket it within " +
                   std::to_string(settings_.pipeline.run.pose_max_gap_s) + " s");
          return true;
        case pipeline::Admission::kNotKeyframe:
          skip(ack, v1::FRAME_OUTCOME_SKIPPED_NOT_KEYFRAME, "moved less than the keyframe thresholds");
          return true;
        case pipeline::Admission::kAdmitted: break;
      }
      const auto t0 = Clock::now();
      const pipeline::StereoFrame raw = decodeStereoFrame(wire, limits_);
      pipeline::PosedPair item = admission_.admit(raw, decision.T_world_raw);
      timings_.add("decode_rectify", msSince(t0));
      // The fused maps travel with the outputs only while a viewer's camera images are due.
      if (viewer::LiveFeed* live = host_.liveFeed()) stages_.setKeepMaps(live->imagesDue());
      if (!stages_.push(std::move(item))) return false;
      ack.set_outcome(v1::FRAME_OUTCOME_PROCESSED);
      ++counters_.frames_processed;
    } catch (const StatusError& e) {
      rejectFrame(ack, e);
    } catch (const Error& e) {
      rejectFrame(ack, toStatusError(e));
    } catch (const std::exception& e) {
      rejectFrame(ack, StatusError(grpc::StatusCode::INTERNAL, std::string("frame failed: ") + e.what()));
    }
    return true;
  }

  // The client closed its side: drain the pipeline into the map.
  grpc::Status finish() {
    stages_.close();
    integrator_.join();
    timings_.set("stereo", stages_.stereoTiming());
    timings_.set("fusion", stages_.fusionTiming());
    if (stages_.failed()) {
      try {
        stages_.rethrowIfFailed();
      } catch (const std::exception& e) {
        return grpc::Status(grpc::StatusCode::INTERNAL, std::string("pipeline failed: ") + e.what());
      }
    }
    if (!integrate_error_.empty()) return grpc::Status(grpc::StatusCode::INTERNAL, integrate_error_);
    return grpc::Status::OK;
  }

 private:
  // The frame's own pose, or one interpolated from the streamed poses (waiting up to
  // server.pose_wait_s for the VIO to catch up). @throws StatusError for a non-finite own pose.
  std::optional<Eigen::Isometry3d> poseOf(const v1::StereoFrame& wire, double t_s) {
    if (wire.has_pose()) return finitePose(wire.pose(), "pose");
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(settings_.server.pose_wait_s));
    return poses_.poseAt(t_s, settings_.pipeline.run.pose_max_gap_s, deadline);
  }

  void rejectFrame(v1::FrameAck& ack, const StatusError& e) {
    ack.set_outcome(v1::FRAME_OUTCOME_REJECTED);
    reject(ack, e);
    ++counters_.frames_rejected;
  }

  void skip(v1::FrameAck& ack, v1::FrameOutcome outcome, const std::string& why) {
    ack.set_outcome(outcome);
    ack.set_message(why);
    ++counters_.frames_skipped;
  }

  void integrateOutputs() {
    while (std::optional<pipeline::FusedOutput> out = stages_.pop()) {
      if (out->points.empty()) continue;
      try {
        const auto t0 = Clock::now();
        host_.integrateFrame(out->points, out->frame.T_world_cam, T_raw_rect_);
        timings_.add("integrate", msSince(t0));
      } catch (const std::exception& e) {
        integrate_error_ = std::string("integration failed: ") + e.what();
        stages_.abort();
      }
      postImages(out->frame);
      stages_.recycle(std::move(out->points));  // its buffers hold the next frame's points
    }
  }

  // The viewer's pictures of a frame never cost the frame: a failure to make them is logged.
  void postImages(const pipeline::DepthFrame& frame) {
    viewer::LiveFeed* live = host_.liveFeed();
    if (!live) return;
    try {
      postCameraImages(*live, frame, baseline_m_, settings_.pipeline.stereo, settings_.server.viewer.image_max_width_px);
    } catch (const std::exception& e) {
      std::cerr << "viewer: no camera images of the frame at t = " << frame.t_s << " s: " << e.what() << std::endl;
    }
  }

  MapHost& host_;
  const ServerSettings& settings_;
  const Eigen::Isometry3d T_raw_rect_;  // the rectified camera in the raw one's frame (CorrectPoses' poses)
  const double baseline_m_;             // of the rectified pair (the viewer's disparity preview)
  pipeline::FrameAdmission admission_;
  const FrameLimits limits_;
  PoseBuffer& poses_;
  IngestCounters& counters_;
  IngestTimings& timings_;
  std::string integrate_error_;
  pipeline::FramePipeline stages_;
  std::thread integrator_;
};

}  // namespace

IngestService::IngestService(MapHost& host, CallGuard& guard, const ServerSettings& settings,
                             std::shared_ptr<const pipeline::Rectifier> rectifier, const CpuPlacement& cpus)
    : host_(host),
      guard_(guard),
      cpus_(cpus),
      settings_(settings),
      rectifier_(std::move(rectifier)),
      poses_(PoseBufferLimits{settings.server.pose_history_s, static_cast<size_t>(settings.server.limits.max_poses),
                              settings.server.pose_max_jump_s}) {}

grpc::Status IngestService::StreamFrames(grpc::ServerContext* context,
                                         grpc::ServerReaderWriter<v1::FrameAck, v1::StereoFrame>* stream) {
  return guard_.runStream(context, "Ingest/StreamFrames", [&] {
    if (!rectifier_) {
      throw StatusError(grpc::StatusCode::FAILED_PRECONDITION,
                        "the server has no stereo calibration: start cenote-server with --calibration");
    }
    StreamSlot slot(frame_streams_, settings_.server.max_frame_streams, "frame streams", "server.max_frame_streams");
    // Decoding, rectification and the pipeline's threads (started by FrameStream) are bulk work.
    CpuScope bulk(cpus_, CpuScope::Side::kBulk);
    FrameStream frames(host_, settings_, *rectifier_, poses_, counters_, timings_);
    acknowledgeEach(stream, [&](const v1::StereoFrame& wire, v1::FrameAck& ack) {
      const bool running = frames.handle(wire, ack);
      ack.set_map_version(host_.map().version());
      return running;
    });
    return frames.finish();
  });
}

grpc::Status IngestService::StreamPoses(grpc::ServerContext* context,
                                        grpc::ServerReaderWriter<v1::PoseAck, v1::PoseStamped>* stream) {
  return guard_.runStream(context, "Ingest/StreamPoses", [&] {
    return acknowledgeIngest(ingest_streams_, settings_.server.limits.max_ingest_streams, stream,
                             [&](const v1::PoseStamped& wire, v1::PoseAck& ack) {
                               ack.set_timestamp_s(wire.timestamp_s());
                               if (!std::isfinite(wire.timestamp_s())) throw invalidArgument("timestamp_s is not finite");
                               poses_.add({wire.timestamp_s(), finitePose(wire.pose(), "pose")});
                             });
  });
}

void IngestService::integrateBatch(const v1::PointBatch& wire, v1::BatchAck& ack) {
  ack.set_timestamp_s(wire.timestamp_s());
  PointBatch batch;
  batch.t_s = wire.timestamp_s();
  batch.origin = finitePoint(wire.origin(), "origin");
  const int64_t limit = settings_.server.limits.max_points_per_batch;
  const std::string limit_name = "server.limits.max_points_per_batch";
  if (!wire.xyz().empty() && !wire.xyz_f32().empty()) {
    throw invalidArgument("xyz and xyz_f32 are both set: send the points in one of them");
  }
  batch.points = wire.xyz_f32().empty() ? pointsFromWire<float>(wire.xyz(), "xyz", limit, limit_name)
                                        : pointsFromWire<float>(wire.xyz_f32(), "xyz_f32", limit, limit_name);
  if (batch.points.empty()) throw invalidArgument("xyz: the batch has no points");
  if (!wire.rgb().empty()) {
    if (wire.rgb().size() != 3 * batch.points.size()) {
      throw invalidArgument("rgb: " + std::to_string(wire.rgb().size()) + " bytes for " +
                            std::to_string(batch.points.size()) + " points (3 per point, or none)");
    }
    batch.colors.resize(batch.points.size());
    const auto* rgb = reinterpret_cast<const uint8_t*>(wire.rgb().data());
    for (size_t i = 0; i < batch.points.size(); ++i) batch.colors[i] = {rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]};
  }
  const mapping::MapDelta delta = host_.integrate(batch);
  ack.set_voxels_updated(delta.voxels_updated);
  ack.set_changed_blocks(delta.changed_blocks.size());
  ack.set_map_version(host_.map().version());
}

grpc::Status IngestService::StreamPoints(grpc::ServerContext* context,
                                         grpc::ServerReaderWriter<v1::BatchAck, v1::PointBatch>* stream) {
  return guard_.runStream(context, "Ingest/StreamPoints", [&] {
    return acknowledgeIngest(ingest_streams_, settings_.server.limits.max_ingest_streams, stream,
                             [&](const v1::PointBatch& wire, v1::BatchAck& ack) { integrateBatch(wire, ack); });
  });
}

grpc::Status IngestService::IntegratePoints(grpc::ServerContext* context, const v1::PointBatch* request,
                                            v1::BatchAck* reply) {
  return guard_.run(context, "Ingest/IntegratePoints", [&] {
    integrateBatch(*request, *reply);
    return grpc::Status::OK;
  });
}

grpc::Status IngestService::CorrectPoses(grpc::ServerContext* context, const v1::PoseCorrection* request,
                                         v1::CorrectionAck* reply) {
  return guard_.run(context, "Ingest/CorrectPoses", [&] {
    const int64_t limit = settings_.server.limits.max_poses;
    if (request->poses_size() > limit) {
      throw resourceExhausted("poses: " + std::to_string(request->poses_size()) +
                              " corrected poses, more than server.limits.max_poses = " + std::to_string(limit));
    }
    std::vector<mapping::CorrectedPose> poses;
    poses.reserve(request->poses_size());
    for (int i = 0; i < request->poses_size(); ++i) {
      const v1::PoseStamped& wire = request->poses(i);
      poses.push_back({wire.timestamp_s(), finitePose(wire.pose(), "poses[" + std::to_string(i) + "].pose")});
    }
    const mapping::CorrectionSummary summary = host_.correctPoses(poses);
    reply->set_frames_moved(summary.frames_moved);
    reply->set_frames_replayed(summary.frames_replayed);
    reply->set_blocks_rebuilt(summary.blocks_rebuilt);
    reply->set_blocks_kept(summary.blocks_kept);
    reply->set_changed_blocks(summary.delta.changed_blocks.size());
    reply->set_map_version(host_.map().version());
    return grpc::Status::OK;
  });
}

}  // namespace cenote::server
