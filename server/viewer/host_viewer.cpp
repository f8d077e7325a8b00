#include "server/viewer/host_viewer.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "io/image/image_io.h"
#include "pipeline/stereo/stereo_matcher.h"

namespace cenote::server {
namespace {

constexpr int kJpegQuality = 80;  // a few tens of kB for a 640x480 view

cv::Mat scaledTo(const cv::Mat& image, int max_width_px, int interpolation) {
  if (image.cols <= max_width_px) return image;
  const double scale = static_cast<double>(max_width_px) / image.cols;
  cv::Mat scaled;
  cv::resize(image, scaled, cv::Size(max_width_px, std::max(1, static_cast<int>(std::lround(image.rows * scale)))), 0, 0,
             interpolation);
  return scaled;
}

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
                                                  viewer::LiveFeed& live, std::vector<std::string> tokens) {
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
  sources.tokens = std::move(tokens);
  sources.server_name = "cenote-server";
  host.setLiveFeed(&live);
  return std::make_unique<viewer::ViewerServer>(settings.server.viewer, std::move(sources));
}

void postCameraImages(viewer::LiveFeed& live, const pipeline::DepthFrame& frame, double baseline_m,
                      const pipeline::StereoConfig& stereo, int max_width_px) {
  if (!live.imagesDue() || frame.color.empty() || frame.depth.empty()) return;
  // Depth and disparity are each other's fx * baseline / x: the stereo stage's conversion makes
  // one from the other (no depth: +inf, painted black), on the scaled-down map.
  const cv::Mat disparity = pipeline::disparityToDepth(scaledTo(frame.depth, max_width_px, cv::INTER_NEAREST),
                                                       frame.K(0, 0), std::abs(baseline_m));
  const cv::Mat preview = io::colorizeMap(disparity, stereo.min_disparity_px,
                                          stereo.min_disparity_px + stereo.num_disparities);
  live.postImages(frame.t_s, io::encodeJpeg(scaledTo(frame.color, max_width_px, cv::INTER_AREA), kJpegQuality),
                  io::encodeJpeg(preview, kJpegQuality));
}

}  // namespace cenote::server
