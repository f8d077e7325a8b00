// host_viewer.h: the live viewer (viewer_server.h) over what cenote-server serves: the map and its
// change feed (MapHost), the ingest's stage timings, the frontiers.
// Threads: as ViewerServer; `host`, `ingest` and `live` must outlive the returned server.
#pragma once

#include <memory>
#include <string>

#include "server/host/map_host.h"
#include "server/services/ingest_service.h"
#include "server/viewer/viewer_server.h"

namespace cenote::server {

// Starts the viewer on settings.server.viewer.listen (null when that is empty) and hands the
// host's integrated batches to `live`. @throws cenote::Error when it cannot listen.
std::unique_ptr<viewer::ViewerServer> startViewer(const ServerSettings& settings, MapHost& host, IngestService& ingest,
                                                  viewer::LiveFeed& live, const std::string& token);

}  // namespace cenote::server
