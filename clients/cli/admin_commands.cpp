// admin_commands.cpp: cenote-cli's operator commands and the update stream.
//   stats                          server statistics: frames, voxels, memory, stage and call timings
//   snapshot PATH [--format F]     writes the map on the server (PATH relative to its snapshot dir)
//   snapshot --download FILE       streams the map to a local file
//       the format follows the extension (mapping/io/map_file_format.h); --format must agree with it
//   watch [--count N] [--region MIN MAX]   one line per map update
//   integrate --points-file F --origin X,Y,Z   one point batch (already in the world frame)
//   clear-box MIN MAX | clear-sphere CENTRE RADIUS | crop CENTRE RADIUS | reset
#include <cstdio>
#include <map>

#include "clients/cli/cli_input.h"
#include "clients/cli/commands.h"
#include "common/error.h"
#include "common/size_format.h"
#include "mapping/io/map_file_format.h"

namespace cenote::cli {

namespace {

using ull = unsigned long long;

// The names of mapping/io/map_file_format.h ("" = from the extension).
client::SnapshotFormat parseFormat(const std::string& name) {
  try {
    return static_cast<client::SnapshotFormat>(mapping::parseMapFileFormat(name));
  } catch (const Error& e) {
    throw CliError(std::string("--") + e.what());
  }
}

void printChange(const char* what, const client::ChangeResult& r) {
  std::printf("%s: %llu blocks changed, map version %llu\n", what, static_cast<ull>(r.changed_blocks),
              static_cast<ull>(r.map_version));
}

void registerStats(CLI::App& app, Connection& connection) {
  CLI::App* cmd = app.add_subcommand("stats", "Server statistics: frames, voxels, memory, timings, calls");
  cmd->callback([&connection] {
    const client::ServerStats s = connection.client().stats();
    std::printf("uptime_s: %.1f\nframes: %llu received, %llu processed, %llu skipped, %llu rejected\n", s.uptime_s,
                static_cast<ull>(s.frames_received), static_cast<ull>(s.frames_processed),
                static_cast<ull>(s.frames_skipped), static_cast<ull>(s.frames_rejected));
    std::printf("batches_integrated: %llu\nposes_received: %llu\nvoxels: %llu occupied, %llu free\n",
                static_cast<ull>(s.batches_integrated), static_cast<ull>(s.poses_received), static_cast<ull>(s.occupied),
                static_cast<ull>(s.free));
    std::printf("memory: map %s, process %s\nmap_version: %llu\nsubscribers: %llu\n",
                formatBytes(static_cast<double>(s.map_memory_bytes)).c_str(),
                formatBytes(static_cast<double>(s.process_memory_bytes)).c_str(), static_cast<ull>(s.map_version),
                static_cast<ull>(s.subscribers));
    if (s.last_snapshot_age_s < 0) {
      std::printf("last_snapshot: none\n");
    } else {
      std::printf("last_snapshot: %.1f s ago\n", s.last_snapshot_age_s);
    }
    for (const auto& stage : s.stages) {
      std::printf("stage %s: median %.3f ms, p95 %.3f ms, %llu runs\n", stage.name.c_str(), stage.median_ms, stage.p95_ms,
                  static_cast<ull>(stage.count));
    }
    for (const auto& m : s.methods) {
      std::printf("call %s: %llu calls, %llu errors, p50 %.3f ms, p99 %.3f ms\n", m.method.c_str(),
                  static_cast<ull>(m.calls), static_cast<ull>(m.errors), m.p50_ms, m.p99_ms);
    }
  });
}

void registerSnapshot(CLI::App& app, Connection& connection) {
  struct Options {
    std::string path;
    std::string format;
    std::string download;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("snapshot", "Write the map on the server, or --download it to a local file");
  cmd->add_option("path", o->path,
                  "File name under the server's snapshot directory; its extension names the format (" +
                      mapping::mapFileFormatTable() + ")");
  auto* download = cmd->add_option("--download", o->download,
                                   "Local file to stream the map into instead (format as for PATH)");
  cmd->add_option("--format", o->format,
                  "vdb, bt, ot, mesh-ply, points-ply, points-pcd: must agree with the extension (needed for a plain .ply)");
  download->excludes(cmd->get_option("path"));
  cmd->callback([o, &connection] {
    if (!o->download.empty()) {
      const uint64_t bytes = connection.client().downloadSnapshot(o->download, parseFormat(o->format));
      std::printf("downloaded %s: %s\n", o->download.c_str(), formatBytes(static_cast<double>(bytes)).c_str());
      return;
    }
    if (o->path.empty()) throw CliError("snapshot: give PATH (on the server) or --download FILE");
    const auto r = connection.client().snapshot(o->path, parseFormat(o->format));
    std::printf("wrote %s on the server: %s, map version %llu\n", r.path.c_str(),
                formatBytes(static_cast<double>(r.bytes)).c_str(), static_cast<ull>(r.map_version));
  });
}

void registerWatch(CLI::App& app, Connection& connection) {
  struct Options {
    uint64_t count = 0;
    std::vector<std::string> region;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "watch", "Print the map's update stream, one line per update (the whole map first, as snapshot lines)");
  cmd->add_option("--count", o->count, "Stop after this many updates (0: until interrupted)");
  cmd->add_option("--region", o->region, "MIN MAX: only blocks holding a voxel whose centre lies in this box")->expected(2);
  cmd->callback([o, &connection] {
    client::SubscribeOptions options;
    if (!o->region.empty()) {
      options.region = {parsePoint(o->region[0], "--region MIN"), parsePoint(o->region[1], "--region MAX")};
      if (options.region.isEmpty()) throw CliError("--region: MIN must not exceed MAX on any axis");
    }
    uint64_t seen = 0;
    connection.client().watch(options, [&](const client::MapUpdate& u) {
      uint64_t occupied = 0, free = 0;
      for (const auto& block : u.blocks) {
        for (client::VoxelState s : block.states) {
          occupied += s == client::VoxelState::kOccupied;
          free += s == client::VoxelState::kFree;
        }
      }
      const char* kind = u.resync ? "resync" : (u.snapshot ? "snapshot" : "change");
      std::printf("update %llu %s%s: %zu blocks (%llu occupied, %llu free voxels in them)", static_cast<ull>(u.sequence),
                  kind, u.snapshot_complete ? " complete" : "", u.blocks.size(), static_cast<ull>(occupied),
                  static_cast<ull>(free));
      if (!u.changed_bounds.isEmpty() && !u.blocks.empty()) {
        std::printf(", bounds %s .. %s", formatPoint(u.changed_bounds.min_m).c_str(),
                    formatPoint(u.changed_bounds.max_m).c_str());
      }
      std::printf("\n");
      std::fflush(stdout);
      return o->count == 0 || ++seen < o->count;
    });
  });
}

void registerIntegrate(CLI::App& app, Connection& connection) {
  struct Options {
    std::string points_file;
    std::string origin;
    double timestamp_s = 0.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("integrate", "Integrate one batch of world-frame points seen from an origin");
  cmd->add_option("--points-file", o->points_file, "File of points, one 'x y z' a line")->required();
  cmd->add_option("--origin", o->origin, "X,Y,Z: sensor origin the points were seen from")->required();
  cmd->add_option("--timestamp", o->timestamp_s, "Seconds");
  cmd->callback([o, &connection] {
    client::PointBatch batch;
    batch.timestamp_s = o->timestamp_s;
    batch.origin_m = parsePoint(o->origin, "--origin");
    batch.points_m = readPointsFile(o->points_file);
    const auto ack = connection.client().integratePoints(batch);
    std::printf("integrated %zu points: %llu voxels updated, %llu blocks changed, map version %llu\n", batch.size(),
                static_cast<ull>(ack.voxels_updated), static_cast<ull>(ack.changed_blocks),
                static_cast<ull>(ack.map_version));
  });
}

// What clear-sphere and crop do with their sphere (MapClient::clearSphere, MapClient::crop).
using SphereEdit = client::ChangeResult (client::MapClient::*)(const Eigen::Vector3d& centre_m, double radius_m);

// A command taking a sphere, CENTRE RADIUS, that it hands to `edit`.
void registerSphereEdit(CLI::App& app, Connection& connection, const char* name, const char* description, SphereEdit edit) {
  struct Sphere {
    std::string centre;
    double radius_m = 0.0;
  };
  auto sphere = std::make_shared<Sphere>();
  CLI::App* cmd = app.add_subcommand(name, description);
  cmd->add_option("centre", sphere->centre, "X,Y,Z")->required();
  cmd->add_option("radius", sphere->radius_m, "Metres")->required();
  cmd->callback([sphere, &connection, name, edit] {
    client::MapClient& map_client = connection.client();  // first: a bad --token-file is reported before a bad CENTRE
    printChange(name, (map_client.*edit)(parsePoint(sphere->centre, std::string(name) + " CENTRE"), sphere->radius_m));
  });
}

void registerEdits(CLI::App& app, Connection& connection) {
  auto box = std::make_shared<std::array<std::string, 2>>();
  CLI::App* clear_box = app.add_subcommand("clear-box", "Forget (make unknown) the voxels in a box");
  clear_box->add_option("min", (*box)[0], "X,Y,Z")->required();
  clear_box->add_option("max", (*box)[1], "X,Y,Z")->required();
  clear_box->callback([box, &connection] {
    printChange("clear-box", connection.client().clearBox(
                                 {parsePoint((*box)[0], "clear-box MIN"), parsePoint((*box)[1], "clear-box MAX")}));
  });

  registerSphereEdit(app, connection, "clear-sphere", "Forget the voxels in a sphere", &client::MapClient::clearSphere);
  registerSphereEdit(app, connection, "crop", "Forget everything outside a sphere", &client::MapClient::crop);

  CLI::App* reset = app.add_subcommand("reset", "Forget the whole map");
  reset->callback([&connection] { printChange("reset", connection.client().reset()); });
}

}  // namespace

void registerAdminCommands(CLI::App& app, Connection& connection) {
  registerStats(app, connection);
  registerSnapshot(app, connection);
  registerWatch(app, connection);
  registerIntegrate(app, connection);
  registerEdits(app, connection);
}

}  // namespace cenote::cli
