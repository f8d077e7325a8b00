#include "tests/server/server_test_util.h"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "mapping/io/map_io.h"

namespace cenote::server::test {

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

}  // namespace cenote::server::test
