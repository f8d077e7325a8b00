// `cenote view MAP`: a saved map (.vdb, .bt, .ot) in the live viewer, without a vehicle or a gRPC
// server: the same Foxglove WebSocket channels and browser page as cenote-server's viewer
// (server/viewer/viewer_server.h), with the map and its frontiers; nothing moves. Runs until
// Ctrl-C or SIGTERM.
#include <pthread.h>

#include <csignal>
#include <filesystem>
#include <iostream>

#include "apps/cenote/commands.h"
#include "apps/cenote/subcommand.h"
#include "common/error.h"
#include "common/text_file.h"
#include "mapping/frontier/frontier_map.h"
#include "mapping/io/map_io.h"
#include "server/viewer/viewer_server.h"

namespace cenote::apps {
namespace {

struct ViewOptions {
  std::string map, listen = "127.0.0.1:8765", token_file, web_dir, tls_cert, tls_key;
  double budget_bytes_per_s = 0.0;
};

int runView(const ViewOptions& o) {
  if (!std::filesystem::exists(o.map)) throw NotFoundError("view: " + o.map + ": no such file");
  // Before any thread starts: the viewer's threads inherit the mask, and this one waits for them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const std::unique_ptr<mapping::OccupancyMap> map = mapping::loadMap(o.map);
  mapping::FrontierMap frontiers(*map);
  frontiers.rebuild();
  server::viewer::ViewerConfig config;
  config.listen = o.listen;
  config.web_dir = o.web_dir;
  config.tls_cert_file = o.tls_cert;
  config.tls_key_file = o.tls_key;
  if (o.budget_bytes_per_s > 0.0) config.budget_bytes_per_s = o.budget_bytes_per_s;
  throwIfInvalid(config.validate(), "view");
  server::viewer::ViewerSources sources;
  sources.map = map.get();
  sources.frontiers = [&frontiers](const Eigen::Vector3d& from_m) { return frontiers.clusters(from_m); };
  if (!o.token_file.empty()) sources.tokens.push_back(readTokenFile(o.token_file, "token file"));
  sources.server_name = "cenote view " + std::filesystem::path(o.map).filename().string();
  server::viewer::ViewerServer viewer(config, std::move(sources));
  const mapping::MapStats stats = map->stats();
  const std::string host = o.listen.substr(0, o.listen.rfind(':'));
  std::cout << "cenote view: " << o.map << " (" << stats.occupied << " occupied voxels) on " << viewer.urls(host)
            << "; Ctrl-C ends" << std::endl;
  int signal = 0;
  sigwait(&signals, &signal);
  viewer.stop();
  return 0;
}

}  // namespace

void registerViewCommand(CLI::App& app) {
  const auto [cmd, o] = addSubcommand<ViewOptions>(
      app, "view", "Show a saved map in the browser viewer / Foxglove (docs/VIEWER.md)", runView);
  cmd->add_option("map", o->map, "the map: .vdb, .bt or .ot")->required();
  cmd->add_option("--listen", o->listen, "HOST:PORT to serve on (default 127.0.0.1:8765; port 0 picks a free one)");
  cmd->add_option("--token-file", o->token_file, "bearer token viewers must send (first line of the file)");
  cmd->add_option("--tls-cert", o->tls_cert, "PEM certificate: serve https:// and wss:// only");
  cmd->add_option("--tls-key", o->tls_key, "PEM private key of --tls-cert");
  cmd->add_option("--web-dir", o->web_dir, "the browser page's files (default: those the build made)");
  cmd->add_option("--budget", o->budget_bytes_per_s, "bytes per second per client (default 1e6)");
}

}  // namespace cenote::apps
