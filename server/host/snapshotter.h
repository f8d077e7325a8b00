// snapshotter.h: writes the map to disk, atomically (mapping/io/map_io.h writes a temporary file
// and renames it), on request, every period while the map changes, and on shutdown. After a crash
// (kill -9) the last complete snapshot is there to `--load`.
// Paths asked for over the wire are relative to the snapshot directory; absolute paths and ".."
// are refused (PERMISSION_DENIED): a client never writes elsewhere on the vehicle.
// A server never overwrites a map it did not load: a <directory>/map.vdb there at start-up that is
// not the file the map was loaded from (`--load`) is renamed to map.<UTC time it was written>.vdb
// (map.20261202T011500Z.vdb, "-2" etc. appended when taken), and the server says so on stderr.
// Quotas: at most max_snapshots such rotated snapshots are kept, and map.vdb with them holds at
// most max_snapshot_bytes; beyond either, the oldest rotated ones are removed first, never map.vdb
// nor the newest rotated one (at start-up, before map.vdb is written anew, the previous session's).
// Threads: any; writes serialise on one mutex (readers of the map are not blocked, see map_io.h).
#pragma once

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cenote/v1/admin.pb.h"
#include "server/host/map_host.h"

namespace cenote::server {

// What becomes of the snapshots already in the directory.
struct SnapshotRetention {
  std::string loaded;              // the file the map was loaded from (--load); empty: none
  int64_t max_snapshots = 10;      // rotated snapshots kept (server.limits.max_snapshots), >= 1
  int64_t max_snapshot_bytes = 0;  // of map.vdb and the rotated ones (server.limits.max_snapshot_bytes); 0: no limit
};

class Snapshotter {
 public:
  // Removes stale temporary files left by a crashed process (removeStaleTemporaries), rotates a
  // map.vdb that was not loaded and applies the quotas.
  // @throws cenote::Error when the directory cannot be created or map.vdb cannot be renamed.
  Snapshotter(const MapHost& host, std::string directory, std::string frame_id, double period_s,
              SnapshotRetention retention = {});
  ~Snapshotter();

  // Writes `relative_path` under the snapshot directory, in the format its extension names
  // (resolveSnapshotFormat). @return the absolute path. @throws StatusError for a refused path
  // (PERMISSION_DENIED) or a format the extension does not name (INVALID_ARGUMENT); cenote::Error
  // of the map writer's kind when the write fails (IoError; ResourceExhaustedError for a full disk).
  std::filesystem::path write(const std::string& relative_path, v1::SnapshotFormat format);
  // Writes to an absolute path chosen by the server (downloads, the periodic snapshot); its
  // extension must name `format` as for write().
  void writeTo(const std::filesystem::path& path, v1::SnapshotFormat format);
  // The periodic / shutdown snapshot: <directory>/map.vdb, when the map changed since the last one;
  // then the byte quota.
  void writeLatest();
  // The rotated snapshots (map.<time>.vdb) in the directory, oldest first (by the time written).
  std::vector<std::filesystem::path> rotatedSnapshots() const;
  // Stops the periodic thread.
  void stop();
  // Seconds since the last snapshot; nullopt when none has been written.
  std::optional<double> lastSnapshotAge() const;
  const std::filesystem::path& directory() const { return directory_; }
  // Removes temporary files (common/atomic_file.h) that a write cut short by a crash left in the
  // snapshot directory; called at construction, before any write of this process starts.
  void removeStaleTemporaries();

 private:
  void periodicLoop();
  // A map.vdb not loaded: renamed to map.<time>.vdb.
  void rotateUnloaded();
  // Removes the oldest rotated snapshots beyond the quotas (never the newest one, never map.vdb).
  void applyQuotas();

  const MapHost& host_;
  const std::filesystem::path directory_;
  const std::string frame_id_;
  const double period_s_;
  const SnapshotRetention retention_;
  std::mutex write_mutex_;
  mutable std::mutex state_mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::optional<uint64_t> saved_version_;
  std::optional<std::chrono::steady_clock::time_point> saved_at_;
  std::thread thread_;
};

// The format of a snapshot file: mapping::resolveMapFileFormat (mapping/io/map_file_format.h) on the
// wire's enum. @throws StatusError INVALID_ARGUMENT naming the path and the format, e.g.
//   "path map.vdb, format SNAPSHOT_FORMAT_POINTS_PLY: map.vdb: the extension .vdb means format vdb,
//    not points-ply (...)"
v1::SnapshotFormat resolveSnapshotFormat(const std::string& path, v1::SnapshotFormat format);

}  // namespace cenote::server
