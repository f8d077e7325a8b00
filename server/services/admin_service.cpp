#include "server/services/admin_service.h"

#include <atomic>
#include <cmath>
#include <fstream>

#include "mapping/io/map_file_format.h"
#include "pipeline/runner/runner.h"
#include "server/wire/wire.h"

namespace cenote::server {
namespace fs = std::filesystem;
namespace {

constexpr size_t kChunkBytes = 1 << 20;

double finiteRadius(double radius_m) {
  if (!std::isfinite(radius_m) || radius_m < 0.0) {
    throw invalidArgument("radius_m = " + std::to_string(radius_m) + ": must be finite and >= 0");
  }
  return radius_m;
}

// Resident set of the process now (statm), in bytes.
uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * 4096;
}

}  // namespace

void AdminService::fillChange(const mapping::MapDelta& delta, v1::ChangeReply* reply) const {
  reply->set_changed_blocks(delta.changed_blocks.size());
  toWire(delta.changed_m, reply->mutable_changed_bounds());
  reply->set_map_version(host_.map().version());
}

grpc::Status AdminService::Snapshot(grpc::ServerContext* context, const v1::SnapshotRequest* request,
                                    v1::SnapshotReply* reply) {
  return guard_.run(context, "Admin/Snapshot", [&] {
    const uint64_t version = host_.map().version();
    const fs::path path = snapshots_.write(request->path(), request->format());
    reply->set_path(path.string());
    reply->set_bytes(fs::file_size(path));
    reply->set_map_version(version);
    return grpc::Status::OK;
  });
}

grpc::Status AdminService::DownloadSnapshot(grpc::ServerContext* context, const v1::SnapshotRequest* request,
                                            grpc::ServerWriter<v1::FileChunk>* writer) {
  return guard_.runStream(context, "Admin/DownloadSnapshot", [&] {
    // Each download writes the whole map to a file first: a few at a time.
    if (++downloads_ > max_downloads_) {
      --downloads_;
      throw resourceExhausted("already " + std::to_string(max_downloads_) +
                              " snapshot downloads running: the limit server.limits.max_snapshot_downloads");
    }
    struct Release {
      std::atomic<int>& n;
      ~Release() { --n; }
    } release{downloads_};
    // Older clients send no file name: the format asked for, VDB when none.
    v1::SnapshotFormat format = request->format();
    if (!request->path().empty()) {
      format = resolveSnapshotFormat(fs::path(request->path()).filename().string(), format);
    } else if (format == v1::SNAPSHOT_FORMAT_UNSPECIFIED) {
      format = v1::SNAPSHOT_FORMAT_VDB;
    } else if (!v1::SnapshotFormat_IsValid(format)) {
      throw invalidArgument("format " + std::to_string(static_cast<int>(format)) + " is not a snapshot format");
    }
    const std::string name = std::string("map") + mapping::extensionOf(static_cast<mapping::MapFileFormat>(format));
    // A private temporary file in the snapshot directory, removed when the download ends.
    static std::atomic<uint64_t> downloads{0};
    const fs::path temp = snapshots_.directory() / (".download." + std::to_string(++downloads) + "." + name);
    struct Remove {
      fs::path path;
      ~Remove() {
        std::error_code ec;
        fs::remove(path, ec);
      }
    } remove{temp};
    snapshots_.writeTo(temp, format);
    std::ifstream in(temp, std::ios::binary);
    const uint64_t total = fs::file_size(temp);
    std::string buffer(kChunkBytes, '\0');
    uint64_t offset = 0;
    do {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      const size_t n = static_cast<size_t>(in.gcount());
      v1::FileChunk chunk;
      chunk.set_offset(offset);
      chunk.set_total_bytes(total);
      chunk.set_data(buffer.data(), n);
      if (offset == 0) chunk.set_file_name(name);
      if (!writer->Write(chunk)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away during the download");
      offset += n;
    } while (offset < total && in);
    return grpc::Status::OK;
  });
}

grpc::Status AdminService::ClearBox(grpc::ServerContext* context, const v1::ClearBoxRequest* request,
                                    v1::ChangeReply* reply) {
  return guard_.run(context, "Admin/ClearBox", [&] {
    fillChange(host_.clearBox(finiteBox(request->box(), "box")), reply);
    return grpc::Status::OK;
  });
}

grpc::Status AdminService::ClearSphere(grpc::ServerContext* context, const v1::ClearSphereRequest* request,
                                       v1::ChangeReply* reply) {
  return guard_.run(context, "Admin/ClearSphere", [&] {
    const Eigen::Vector3d centre = finitePoint(request->centre(), "centre");
    fillChange(host_.clearSphere(centre, finiteRadius(request->radius_m())), reply);
    return grpc::Status::OK;
  });
}

grpc::Status AdminService::Crop(grpc::ServerContext* context, const v1::CropRequest* request, v1::ChangeReply* reply) {
  return guard_.run(context, "Admin/Crop", [&] {
    const Eigen::Vector3d centre = finitePoint(request->centre(), "centre");
    fillChange(host_.cropToRadius(centre, finiteRadius(request->radius_m())), reply);
    return grpc::Status::OK;
  });
}

grpc::Status AdminService::Reset(grpc::ServerContext* context, const v1::ResetRequest*, v1::ChangeReply* reply) {
  return guard_.run(context, "Admin/Reset", [&] {
    fillChange(host_.reset(), reply);
    return grpc::Status::OK;
  });
}

grpc::Status AdminService::GetStats(grpc::ServerContext* context, const v1::StatsRequest*, v1::Stats* reply) {
  return guard_.run(context, "Admin/GetStats", [&] {
    const IngestCounters& c = ingest_.counters();
    reply->set_uptime_s(std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count());
    reply->set_frames_received(c.frames_received);
    reply->set_frames_processed(c.frames_processed);
    reply->set_frames_skipped(c.frames_skipped);
    reply->set_frames_rejected(c.frames_rejected);
    reply->set_batches_integrated(host_.batchesIntegrated());
    reply->set_poses_received(ingest_.poses().received());
    const mapping::MapStats stats = host_.map().stats();
    reply->set_occupied(stats.occupied);
    reply->set_free(stats.free);
    reply->set_map_memory_bytes(stats.memory_bytes);
    reply->set_process_memory_bytes(residentBytes());
    reply->set_map_version(host_.map().version());
    for (const StageSummaryNamed& s : ingest_.stageTimings()) {
      v1::StageTiming* t = reply->add_stages();
      t->set_name(s.name);
      t->set_median_ms(s.summary.median_ms);
      t->set_p95_ms(s.summary.p95_ms);
      t->set_count(s.summary.frames);
    }
    for (const MethodSummary& m : guard_.summaries()) {
      v1::MethodStats* out = reply->add_methods();
      out->set_method(m.method);
      out->set_calls(m.calls);
      out->set_errors(m.errors);
      out->set_p50_ms(m.p50_ms);
      out->set_p99_ms(m.p99_ms);
    }
    reply->set_subscribers(host_.feed().subscribers());
    reply->set_last_snapshot_age_s(snapshots_.lastSnapshotAge().value_or(-1.0));
    return grpc::Status::OK;
  });
}

}  // namespace cenote::server
