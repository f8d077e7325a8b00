#include "server/viewer/host_viewer.h"

namespace cenote::server {
namespace {

// The host's change feed, read without waiting.
class FeedSource final : public viewer::ChangeSource {
 public:
  explicit FeedSource(ChangeFeed& feed) : feed_(feed), subscription_(feed.subscribe()) {}
  ~FeedSource() override { feed_.unsubscribe(subscription_); }

  Next poll(std::vector<mapping::BlockIndex>& blocks) override {
    MapChange change;
    switch (subscription_->next(change, std::chrono::milliseconds(0))) {
      case Subscription::Next::kChange: blocks = std::move(change.delta.changed_blocks); return Next::kChange;
      case Subscription::Next::kResync: return Next::kResync;
      case Subscription::Next::kTimeout: return Next::kNone;
      case Subscription::Next::kClosed: return Next::kClosed;
    }
    return Next::kNone;
  }

 private:
  ChangeFeed& feed_;
  std::shared_ptr<Subscription> subscription_;
};

}  // namespace

std::unique_ptr<viewer::ViewerServer> startViewer(const ServerSettings& settings, MapHost& host, IngestService& ingest,
                                                  viewer::LiveFeed& live, const std::string& token) {
  if (!settings.server.viewer.enabled()) return nullptr;
  viewer::ViewerSources sources;
  sources.map = &host.map();
  sources.subscribe = [&host] { return std::make_unique<FeedSource>(host.feed()); };
  sources.live = &live;
  // The frontiers as the host last derived them: a viewer never makes it derive (that keeps the
  // distance field current too, a third of the server's CPU while ingesting); they follow the map
  // while planners ask for frontiers or distances (map_host.h).
  sources.frontiers = [&host](const Eigen::Vector3d& from_m) { return host.frontiers().clusters(from_m); };
  sources.stages = [&ingest] {
    std::vector<viewer::StageRate> rates;
    for (const StageSummaryNamed& s : ingest.stageTimings())
      rates.push_back({s.name, s.summary.median_ms, s.summary.frames});
    return rates;
  };
  sources.batches = [&host] { return host.batchesIntegrated(); };
  sources.frame_id = settings.server.frame_id;
  sources.token = token;
  sources.server_name = "cenote-server";
  host.setLiveFeed(&live);
  return std::make_unique<viewer::ViewerServer>(settings.server.viewer, std::move(sources));
}

}  // namespace cenote::server
