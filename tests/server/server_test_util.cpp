#include "tests/server/server_test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

#include "mapping/io/map_io.h"

namespace cenote::server::test {

namespace fs = std::filesystem;

fs::path scratchDir(const std::string& suite, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cenote-" + suite + "-" + std::to_string(getpid())) / name;
  fs::create_directories(dir);
  return dir;
}

std::string writeConfig(const fs::path& dir, const std::string& yaml) {
  const fs::path path = dir / "config.yaml";
  std::ofstream(path) << yaml;
  return path.string();
}

std::pair<int, std::string> runServerToExit(const fs::path& dir, const std::string& args) {
  const fs::path log = dir / "server.log";
  const int status = std::system((std::string(CENOTE_SERVER_BINARY) + " " + args + " > " + log.string() + " 2>&1").c_str());
  std::ifstream in(log);
  return {WEXITSTATUS(status), std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>())};
}

MapDifference compareMaps(const mapping::OccupancyMap& a, const mapping::OccupancyMap& b) {
  const auto access_a = a.constAccessor();
  const auto access_b = b.constAccessor();
  std::set<std::array<int, 3>> blocks;
  for (const auto& access : {&access_a, &access_b})
    for (const mapping::BlockIndex& block : access->knownBlocks()) blocks.insert({block.x(), block.y(), block.z()});
  MapDifference diff;
  for (const auto& [x, y, z] : blocks) {
    for (int offset = 0; offset < mapping::kBlockVoxels; ++offset) {
      const mapping::VoxelIndex ijk = mapping::voxelOfOffset(mapping::BlockIndex(x, y, z), offset);
      float la = 0.0f, lb = 0.0f;
      const bool known_a = access_a.logOdds(ijk, la), known_b = access_b.logOdds(ijk, lb);
      if (!known_a && !known_b) continue;
      ++diff.known;
      if (access_a.state(ijk) != access_b.state(ijk)) ++diff.different_state;
      if (known_a != known_b || la != lb) ++diff.different_log_odds;
    }
  }
  return diff;
}

std::unique_ptr<mapping::OccupancyMap> downloadMap(v1::Admin::Stub& admin, const std::string& dir) {
  const std::string path = dir + "/downloaded.vdb";
  auto context = contextWithDeadline();
  v1::SnapshotRequest request;
  request.set_format(v1::SNAPSHOT_FORMAT_VDB);
  auto reader = admin.DownloadSnapshot(context.get(), request);
  std::ofstream out(path, std::ios::binary);
  v1::FileChunk chunk;
  while (reader->Read(&chunk)) out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
  out.close();
  const grpc::Status status = reader->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
  return mapping::loadMap(path);
}

v1::PointBatch wallBatch(double wall_x_m, double half_m, double spacing_m, double t_s) {
  v1::PointBatch batch;
  batch.set_timestamp_s(t_s);
  batch.mutable_origin();  // (0, 0, 0)
  for (double y = -half_m; y <= half_m; y += spacing_m) {
    for (double z = -half_m; z <= half_m; z += spacing_m) {
      batch.add_xyz(wall_x_m);
      batch.add_xyz(y);
      batch.add_xyz(z);
    }
  }
  return batch;
}

namespace {

// The value of `key` in a /proc status file ("Cpus_allowed_list:\t0-1" -> "0-1").
std::string statusField(const fs::path& status, const std::string& key) {
  std::ifstream in(status);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key + ":", 0) == 0) return line.substr(line.find_first_not_of(" \t", key.size() + 1));
  }
  return "";
}

// Field 19 of /proc/<pid>/task/<tid>/stat (after the parenthesised name, which may hold spaces).
int niceOf(const fs::path& stat) {
  std::ifstream in(stat);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string field;
  for (int i = 3; fields >> field; ++i)
    if (i == 19) return std::stoi(field);
  return 0;
}

}  // namespace

std::vector<ThreadInfo> threadsOf(pid_t pid) {
  std::vector<ThreadInfo> threads;
  std::error_code error;  // a thread may end while we read: skipped
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", error)) {
    ThreadInfo info{statusField(task.path() / "status", "Name"), statusField(task.path() / "status", "Cpus_allowed_list"),
                    niceOf(task.path() / "stat")};
    if (!info.name.empty()) threads.push_back(info);
  }
  return threads;
}

std::string cpusOfThisProcess() { return statusField("/proc/self/status", "Cpus_allowed_list"); }

}  // namespace cenote::server::test
