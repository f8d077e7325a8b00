// host_viewer.h: the live viewer (viewer_server.h) over what cenote-server serves: the map and its
// change feed (MapHost), the ingest's stage timings, the frontiers, the camera images.
// Threads: as ViewerServer; `host`, `ingest` and `live` must outlive the returned server.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pipeline/frame/frames.h"
#include "pipeline/stereo/stereo_config.h"
#include "server/host/map_host.h"
#include "server/services/ingest_service.h"
#include "server/viewer/viewer_server.h"

namespace cenote::server {

// Starts the viewer on settings.server.viewer.listen (null when that is empty) and hands the
// host's integrated batches to `live`. tokens: those that let a viewer in (the server's operator
// and read-only tokens; none: no authentication). @throws cenote::Error when it cannot listen.
std::unique_ptr<viewer::ViewerServer> startViewer(const ServerSettings& settings, MapHost& host, IngestService& ingest,
                                                  viewer::LiveFeed& live, std::vector<std::string> tokens);

// One fused frame's camera images for the viewer, when `live` wants them now (imagesDue): its
// rectified left image and its depth as a disparity preview (fx * baseline / depth, coloured as
// `cenote stereo --out-preview` colours a disparity map over the search range of `stereo`;
// black without depth), both scaled down to at most max_width_px and JPEG-encoded here, on the
// caller's (ingest) thread. A frame without its maps (FusedOutput without kept maps) is passed over.
void postCameraImages(viewer::LiveFeed& live, const pipeline::DepthFrame& frame, double baseline_m,
                      const pipeline::StereoConfig& stereo, int max_width_px);

}  // namespace cenote::server
