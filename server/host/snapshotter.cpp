#include "server/host/snapshotter.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <regex>
#include <tuple>

#include "common/atomic_file.h"
#include "common/error.h"
#include "mapping/io/map_io.h"
#include "io/cloud/pcd_io.h"
#include "server/wire/status_error.h"

namespace cenote::server {
namespace fs = std::filesystem;

namespace {

static_assert(static_cast<int>(mapping::MapFileFormat::kPointsPcd) == v1::SNAPSHOT_FORMAT_POINTS_PCD &&
                  static_cast<int>(mapping::MapFileFormat::kMeshPly) == v1::SNAPSHOT_FORMAT_MESH_PLY &&
                  static_cast<int>(mapping::MapFileFormat::kVdb) == v1::SNAPSHOT_FORMAT_VDB,
              "mapping::MapFileFormat numbers are admin.proto's SnapshotFormat values");

}  // namespace

v1::SnapshotFormat resolveSnapshotFormat(const std::string& path, v1::SnapshotFormat format) {
  if (!v1::SnapshotFormat_IsValid(format)) {
    throw invalidArgument("path " + path + ", format " + std::to_string(static_cast<int>(format)) +
                          ": not a snapshot format (" + mapping::mapFileFormatTable() + ")");
  }
  try {
    return static_cast<v1::SnapshotFormat>(
        mapping::resolveMapFileFormat(path, static_cast<mapping::MapFileFormat>(format)));
  } catch (const Error& e) {
    throw invalidArgument("path " + path + ", format " + v1::SnapshotFormat_Name(format) + ": " + e.what());
  }
}

Snapshotter::Snapshotter(const MapHost& host, std::string directory, std::string frame_id, double period_s,
                         SnapshotRetention retention)
    : host_(host),
      directory_(fs::absolute(directory)),
      frame_id_(std::move(frame_id)),
      period_s_(period_s),
      retention_(std::move(retention)) {
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec) throw Error("snapshot directory " + directory_.string() + " cannot be created: " + ec.message());
  removeStaleTemporaries();
  rotateUnloaded();
  applyQuotas();
  if (period_s_ > 0.0) thread_ = std::thread([this] { periodicLoop(); });
}

Snapshotter::~Snapshotter() { stop(); }

void Snapshotter::removeStaleTemporaries() {
  std::error_code ec;
  for (fs::recursive_directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec) || !isTemporaryPath(it->path().string())) continue;
    std::fprintf(stderr, "cenote-server: removing %s, left by a snapshot that did not finish\n", it->path().c_str());
    std::error_code remove_ec;
    fs::remove(it->path(), remove_ec);
  }
}

void Snapshotter::rotateUnloaded() {
  const fs::path latest = directory_ / "map.vdb";
  std::error_code ec;
  if (!fs::exists(latest, ec)) return;
  if (!retention_.loaded.empty() && fs::equivalent(retention_.loaded, latest, ec)) return;
  // Named after the time it was written: the end of the session it holds.
  const auto written = std::chrono::file_clock::to_sys(fs::last_write_time(latest));
  const std::time_t t = std::chrono::system_clock::to_time_t(
      std::chrono::time_point_cast<std::chrono::system_clock::duration>(written));
  std::tm utc{};
  gmtime_r(&t, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  fs::path rotated = directory_ / ("map." + std::string(stamp) + ".vdb");
  for (int n = 2; fs::exists(rotated, ec); ++n)
    rotated = directory_ / ("map." + std::string(stamp) + "-" + std::to_string(n) + ".vdb");
  fs::rename(latest, rotated, ec);
  if (ec) throw IoError("cannot keep " + latest.string() + " as " + rotated.string() + ": " + ec.message());
  std::fprintf(stderr, "cenote-server: %s was not loaded (%s): kept as %s; this server writes a new map.vdb\n",
               latest.c_str(), retention_.loaded.empty() ? "no --load" : ("--load " + retention_.loaded).c_str(),
               rotated.filename().c_str());
}

std::vector<fs::path> Snapshotter::rotatedSnapshots() const {
  static const std::regex kRotated(R"(map\.(\d{8}T\d{6}Z)(-(\d+))?\.vdb)");
  // By the time written, then the time in the name, then the number after it (none: 1).
  std::vector<std::tuple<fs::file_time_type, std::string, int, fs::path>> found;
  std::error_code ec;
  for (fs::directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
    std::smatch m;
    const std::string name = it->path().filename().string();
    if (!it->is_regular_file(ec) || !std::regex_match(name, m, kRotated)) continue;
    found.emplace_back(fs::last_write_time(it->path(), ec), m[1].str(), m[3].matched ? std::stoi(m[3].str()) : 1,
                       it->path());
  }
  std::sort(found.begin(), found.end());
  std::vector<fs::path> out;
  for (auto& f : found) out.push_back(std::move(std::get<3>(f)));
  return out;
}

void Snapshotter::applyQuotas() {
  std::vector<fs::path> rotated = rotatedSnapshots();
  std::error_code ec;
  uint64_t bytes = fs::exists(directory_ / "map.vdb", ec) ? fs::file_size(directory_ / "map.vdb", ec) : 0;
  for (const fs::path& p : rotated) bytes += fs::file_size(p, ec);
  const uint64_t max_bytes = static_cast<uint64_t>(retention_.max_snapshot_bytes);
  size_t oldest = 0;
  while (rotated.size() - oldest > 1 && (static_cast<int64_t>(rotated.size() - oldest) > retention_.max_snapshots ||
                                         (max_bytes > 0 && bytes > max_bytes))) {
    const fs::path& p = rotated[oldest++];
    const uint64_t size = fs::file_size(p, ec);
    if (!fs::remove(p, ec)) continue;
    bytes -= size;
    std::fprintf(stderr,
                 "cenote-server: removed %s, the oldest snapshot beyond server.limits.max_snapshots = %lld / "
                 "max_snapshot_bytes = %lld\n",
                 p.c_str(), static_cast<long long>(retention_.max_snapshots),
                 static_cast<long long>(retention_.max_snapshot_bytes));
  }
}

void Snapshotter::stop() {
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

fs::path Snapshotter::write(const std::string& relative_path, v1::SnapshotFormat format) {
  const fs::path relative(relative_path);
  if (relative_path.empty()) throw invalidArgument("path: empty; give a file name such as map.vdb");
  if (relative.is_absolute()) {
    throw StatusError(
        grpc::StatusCode::PERMISSION_DENIED,
        "path " + relative_path + " is absolute; snapshots are written under the server's snapshot directory");
  }
  for (const fs::path& part : relative) {
    if (part == "..") {
      throw StatusError(grpc::StatusCode::PERMISSION_DENIED, "path " + relative_path + " leaves the snapshot directory");
    }
  }
  format = resolveSnapshotFormat(relative_path, format);
  const fs::path target = directory_ / relative;
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  writeTo(target, format);
  return target;
}

void Snapshotter::writeTo(const fs::path& path, v1::SnapshotFormat format) {
  format = resolveSnapshotFormat(path.filename().string(), format);
  std::lock_guard<std::mutex> lock(write_mutex_);
  const mapping::OccupancyMap& map = host_.map();
  switch (format) {
    case v1::SNAPSHOT_FORMAT_VDB:
    case v1::SNAPSHOT_FORMAT_BT:
    case v1::SNAPSHOT_FORMAT_OT: mapping::saveMap(map, path.string(), frame_id_); break;
    case v1::SNAPSHOT_FORMAT_MESH_PLY: mapping::exportMeshPly(map, path.string()); break;
    case v1::SNAPSHOT_FORMAT_POINTS_PLY: mapping::exportOccupiedPointsPly(map, path.string()); break;
    case v1::SNAPSHOT_FORMAT_POINTS_PCD: {
      const PointBatch centres = mapping::occupiedVoxelCentres(map);
      io::writePcd(path.string(), centres.points, centres.colors);
      break;
    }
    default: throw invalidArgument("format " + std::to_string(static_cast<int>(format)) + " is not a snapshot format");
  }
}

void Snapshotter::writeLatest() {
  const uint64_t version = host_.map().version();
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    if (saved_version_ && *saved_version_ == version) return;
  }
  writeTo(directory_ / "map.vdb", v1::SNAPSHOT_FORMAT_VDB);
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    saved_version_ = version;
    saved_at_ = std::chrono::steady_clock::now();
  }
  std::lock_guard<std::mutex> lock(write_mutex_);
  applyQuotas();
}

std::optional<double> Snapshotter::lastSnapshotAge() const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (!saved_at_) return std::nullopt;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - *saved_at_).count();
}

void Snapshotter::periodicLoop() {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(period_s_));
  std::unique_lock<std::mutex> lock(state_mutex_);
  while (!wake_.wait_for(lock, period, [&] { return stop_; })) {
    lock.unlock();
    try {
      writeLatest();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cenote-server: periodic snapshot failed: %s\n", e.what());
    }
    lock.lock();
  }
}

}  // namespace cenote::server
