#include "server/viewer/viewer_feed.h"

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "common/locked_copy.h"
#include "common/thread_name.h"
#include "server/viewer/block_sync.h"
#include "server/viewer/foxglove_schemas.h"
#include "server/viewer/scene_messages.h"

namespace cenote::server::viewer {
namespace {

using Clock = std::chrono::steady_clock;

uint64_t nowNs() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
}

Channel channel(uint32_t id, const char* topic, const char* schema_name, const std::string& schema) {
  return {id, topic, "json", schema_name, schema, "jsonschema"};
}

}  // namespace

const std::vector<Channel>& viewerChannels() {
  static const std::vector<Channel> channels = {
      channel(kMapChannel, "/map", "foxglove.SceneUpdate", sceneUpdateSchema()),
      channel(kCameraChannel, "/camera", "foxglove.FrameTransform", frameTransformSchema()),
      channel(kTrajectoryChannel, "/trajectory", "foxglove.PosesInFrame", posesInFrameSchema()),
      channel(kCloudChannel, "/cloud", "foxglove.PointCloud", pointCloudSchema()),
      channel(kFrontierChannel, "/frontiers", "foxglove.SceneUpdate", sceneUpdateSchema()),
      channel(kStatsChannel, "/stats", "cenote.MapStats", mapStatsSchema()),
      channel(kImageChannel, "/camera/image", "foxglove.CompressedImage", compressedImageSchema()),
      channel(kDisparityChannel, "/camera/disparity", "foxglove.CompressedImage", compressedImageSchema()),
  };
  return channels;
}

void ClientLink::greet(const std::string& server_name, const std::string& session_id) {
  send(serverInfoMessage(server_name, session_id), false);
  send(advertiseMessage(viewerChannels()), false);
}

void ClientLink::receiveText(std::string_view text) {
  std::vector<std::string> problems;
  try {
    const ClientRequest request = parseClientMessage(text);
    std::lock_guard<std::mutex> lock(mutex_);
    problems = subscriptions_.apply(request, viewerChannels());
  } catch (const Error& e) {
    problems.push_back(e.what());
  }
  for (const std::string& p : problems) send(statusMessage(StatusLevel::kError, p), false);
}

void ClientLink::receiveBinary() {
  send(statusMessage(StatusLevel::kError,
                     "binary client messages are not supported: this server does not offer clientPublish or services"),
       false);
}

std::optional<uint32_t> ClientLink::subscriptionOf(uint32_t channel) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return subscriptions_.subscriptionOf(channel);
}

struct FeedWorker::Client {
  std::shared_ptr<ClientLink> link;
  std::optional<uint32_t> map_subscription;  // the one `sync` was started for
  std::unique_ptr<BlockSync> sync;
  double allowance_bytes = 0.0;
  uint64_t camera_version = 0, trajectory_version = 0, cloud_version = 0, image_version = 0;
  std::optional<uint32_t> frontier_subscription;
  Clock::time_point next_period{};
};

FeedWorker::FeedWorker(const ViewerConfig& config, const ViewerSources& sources)
    : config_(config), sources_(sources), thread_([this] {
        nameThisThread("viewer-feed");
        loop();
      }) {}

FeedWorker::~FeedWorker() { stop(); }

void FeedWorker::add(std::shared_ptr<ClientLink> link) {
  std::lock_guard<std::mutex> lock(mutex_);
  arrived_.push_back(std::move(link));
  wake_.notify_one();
}

void FeedWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

size_t FeedWorker::clients() const { return lockedCopy(mutex_, clients_); }

void FeedWorker::loop() {
  std::vector<std::shared_ptr<Client>> clients;
  std::unique_ptr<ChangeSource> changes;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.tick_s));
  Clock::time_point last = Clock::now();
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (clients.empty()) {
        wake_.wait(lock, [&] { return stop_ || !arrived_.empty(); });
      } else {
        wake_.wait_for(lock, period, [&] { return stop_; });
      }
      if (stop_) break;
      for (auto& link : arrived_) {
        auto client = std::make_shared<Client>();
        client->link = std::move(link);
        client->allowance_bytes = config_.budget_bytes_per_s;  // a second's worth to start with
        clients.push_back(std::move(client));
      }
      arrived_.clear();
      clients.erase(std::remove_if(clients.begin(), clients.end(), [](const auto& c) { return !c->link->isOpen(); }),
                    clients.end());
      clients_ = clients.size();
    }
    if (clients.empty()) {
      changes.reset();  // no subscription to the map's changes while nobody watches
      if (sources_.live) sources_.live->setWanted(false, false);
      continue;
    }
    // Subscribe before any client reads the whole map: a change made meanwhile is sent twice,
    // never missed.
    if (!changes && sources_.subscribe) changes = sources_.subscribe();
    const Clock::time_point now = Clock::now();
    const double dt_s = std::chrono::duration<double>(now - last).count();
    last = now;

    std::vector<mapping::BlockIndex> blocks;
    bool resync = false;
    while (changes) {
      blocks.clear();
      const ChangeSource::Next next = changes->poll(blocks);
      if (next == ChangeSource::Next::kChange) {
        for (auto& c : clients)
          if (c->sync) c->sync->markChanged(blocks);
      } else if (next == ChangeSource::Next::kResync) {
        resync = true;
      } else {
        break;
      }
    }
    if (resync) {
      std::vector<mapping::BlockIndex> known;
      {
        const auto access = sources_.map->constAccessor();
        known = access.knownBlocks();
      }
      for (auto& c : clients)
        if (c->sync) c->sync->markAll(known);
    }
    if (sources_.live) {
      auto anyWants = [&](uint32_t channel) {
        return std::any_of(clients.begin(), clients.end(),
                           [channel](const auto& c) { return c->link->subscriptionOf(channel).has_value(); });
      };
      sources_.live->setWanted(anyWants(kCloudChannel), anyWants(kImageChannel) || anyWants(kDisparityChannel));
    }
    tick(clients, dt_s);
  }
  if (sources_.live) sources_.live->setWanted(false, false);
}

void FeedWorker::tick(std::vector<std::shared_ptr<Client>>& clients, double dt_s) {
  const mapping::OccupancyMap& map = *sources_.map;
  const uint64_t time_ns = nowNs();
  const Clock::time_point now = Clock::now();
  const double rate = config_.budget_bytes_per_s;
  std::optional<std::pair<Eigen::Isometry3d, uint64_t>> camera;
  if (sources_.live) camera = sources_.live->latest();
  const Eigen::Vector3d camera_m = camera ? Eigen::Vector3d(camera->first.translation()) : Eigen::Vector3d::Zero();

  // Made at most once per tick, for whichever clients want them.
  std::optional<mapping::MapStats> map_stats;
  std::optional<std::string> frontiers_json, trajectory_json;
  uint64_t trajectory_version = 0;
  std::optional<LiveFeed::Images> images;
  std::optional<std::pair<std::string, std::string>> image_json;  // left, disparity

  for (auto& c : clients) {
    ClientLink& link = *c->link;
    c->allowance_bytes = std::min(c->allowance_bytes + rate * dt_s, rate);
    // A second's worth still unsent: the client (or its link) is slow. Make nothing new for it;
    // what it misses meanwhile waits as dirty blocks and newest values.
    if (link.unsentBytes() > static_cast<size_t>(rate)) continue;
    auto emit = [&](uint32_t channel_id, const std::string& payload) {
      const std::optional<uint32_t> subscription = link.subscriptionOf(channel_id);
      if (!subscription) return;
      std::string frame = messageDataFrame(*subscription, time_ns, payload);
      c->allowance_bytes -= static_cast<double>(frame.size());
      bytes_sent_ += frame.size();
      link.send(std::move(frame), true);
    };

    // The map: a new subscription starts from the whole map.
    const std::optional<uint32_t> map_subscription = link.subscriptionOf(kMapChannel);
    if (map_subscription != c->map_subscription) {
      c->map_subscription = map_subscription;
      c->sync.reset();
      if (map_subscription) {
        c->sync = std::make_unique<BlockSync>(sources_.frame_id,
                                              config_.color_by == "height" ? ColorBy::kHeight : ColorBy::kImage,
                                              config_.refresh_s, config_.resend_s);
        const auto access = map.constAccessor();
        c->sync->markAll(access.knownBlocks());
      }
    }
    if (camera && camera->second != c->camera_version && link.subscriptionOf(kCameraChannel)) {
      emit(kCameraChannel, frameTransformJson(time_ns, sources_.frame_id, camera->first));
      c->camera_version = camera->second;
    }

    const std::optional<uint32_t> frontier_subscription = link.subscriptionOf(kFrontierChannel);
    const bool new_frontier_subscription = frontier_subscription && frontier_subscription != c->frontier_subscription;
    c->frontier_subscription = frontier_subscription;
    if (now >= c->next_period || new_frontier_subscription) {
      c->next_period = now +
                       std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.stats_period_s));
      if (link.subscriptionOf(kStatsChannel)) {
        if (!map_stats) map_stats = map.stats();
        nlohmann::json stages = nlohmann::json::array();
        if (sources_.stages) {
          for (const StageRate& s : sources_.stages()) {
            stages.push_back({{"name", s.name},
                              {"median_ms", s.median_ms},
                              {"fps", s.median_ms > 0.0 ? 1000.0 / s.median_ms : 0.0},
                              {"frames", s.frames}});
          }
        }
        const nlohmann::json stats = {{"timestamp", {{"sec", time_ns / 1000000000ull}, {"nsec", time_ns % 1000000000ull}}},
                                      {"voxel_size_m", map_stats->voxel_size_m},
                                      {"occupied", map_stats->occupied},
                                      {"free", map_stats->free},
                                      {"memory_bytes", map_stats->memory_bytes},
                                      {"map_version", map.version()},
                                      {"batches", sources_.batches ? sources_.batches() : 0},
                                      {"stages", stages},
                                      {"bytes_sent", bytes_sent_.load()},
                                      {"clients", clients.size()},
                                      {"client_dirty_blocks", c->sync ? c->sync->dirtyBlocks() : 0},
                                      {"client_coarse_blocks", c->sync ? c->sync->coarseBlocks() : 0},
                                      {"client_stale_blocks", c->sync ? c->sync->staleBlocks() : 0}};
        emit(kStatsChannel, stats.dump());
      }
      if (frontier_subscription && sources_.frontiers) {
        if (!frontiers_json) frontiers_json = frontierSceneJson(time_ns, sources_.frame_id, sources_.frontiers(camera_m));
        emit(kFrontierChannel, *frontiers_json);
      }
      if (sources_.live && link.subscriptionOf(kTrajectoryChannel)) {
        if (!trajectory_json) {
          const LiveFeed::Poses poses = sources_.live->poses();
          trajectory_version = poses.version;
          trajectory_json = posesInFrameJson(time_ns, sources_.frame_id, poses.trajectory);
        }
        if (trajectory_version != c->trajectory_version) {
          emit(kTrajectoryChannel, *trajectory_json);
          c->trajectory_version = trajectory_version;
        }
      }
    }

    // The newest camera images go before the map (a second's image is a few tens of kB), when
    // the budget has room for both.
    if (sources_.live && (link.subscriptionOf(kImageChannel) || link.subscriptionOf(kDisparityChannel))) {
      if (!images) images = sources_.live->images();
      if (images->version != 0 && images->version != c->image_version) {
        if (!image_json) {
          image_json = {compressedImageJson(time_ns, *images->left_jpeg),
                        compressedImageJson(time_ns, *images->disparity_jpeg)};
        }
        if (c->allowance_bytes >= static_cast<double>(image_json->first.size() + image_json->second.size())) {
          emit(kImageChannel, image_json->first);
          emit(kDisparityChannel, image_json->second);
          c->image_version = images->version;
        }
      }
    }

    // The latest cloud gets a quarter of the budget while the map has more to send.
    const bool wants_cloud = sources_.live && link.subscriptionOf(kCloudChannel).has_value();
    if (c->sync && c->allowance_bytes > 0.0) {
      const double budget = c->allowance_bytes * (wants_cloud ? 0.75 : 1.0);
      SyncStep step;
      {
        const auto access = map.constAccessor();
        step = c->sync->next(access, camera_m, budget, time_ns);
      }
      if (!step.message.empty()) emit(kMapChannel, step.message);
    }
    if (wants_cloud) {
      const auto [cloud, version] = sources_.live->cloud();
      const double bytes = 300.0 + (cloud ? 20.0 * static_cast<double>(cloud->size()) : 0.0);
      if (cloud && version != c->cloud_version && c->allowance_bytes >= bytes) {
        emit(kCloudChannel, pointCloudJson(time_ns, sources_.frame_id, *cloud));
        c->cloud_version = version;
      }
    }
  }
}

}  // namespace cenote::server::viewer
