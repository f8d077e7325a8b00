// map_client_update_test.cpp: what changes the map, through the C++ client on a real cenote-server:
// the update stream kept as a MapMirror (equal to the server's map after integrations and
// clearing, for live and late subscribers), the point stream (a bad batch rejected in its ack, the
// stream going on), admin edits and snapshots, and 8 query clients running while points are
// ingested (zero errors).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "clients/cpp/map_client.h"
#include "clients/cpp/map_mirror.h"
#include "mapping/io/map_io.h"
#include "mapping/query/map_query.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/clients/cpp/wall_scene.h"

namespace cenote::client::test {
namespace {

using VoxelKey = std::tuple<int, int, int>;

std::map<VoxelKey, VoxelState> serverVoxels(MapClient& map) {
  std::map<VoxelKey, VoxelState> out;
  const MapInfo info = map.info();
  if (info.bounds.isEmpty()) return out;
  const Box box{(info.bounds.min_m.array() - kVoxel_m).matrix(), (info.bounds.max_m.array() + kVoxel_m).matrix()};
  const ExtractedVoxels known = map.extract(box, false);
  for (size_t i = 0; i < known.size(); ++i) out[{known.ijk[i].x(), known.ijk[i].y(), known.ijk[i].z()}] = known.states[i];
  return out;
}

std::map<VoxelKey, VoxelState> mirrorVoxels(const MapMirror& mirror) {
  std::map<VoxelKey, VoxelState> out;
  for (const auto& [ijk, state] : mirror.knownVoxels()) out[{ijk.x(), ijk.y(), ijk.z()}] = state;
  return out;
}

// Waits until the mirror has applied the update of `version` (or 20 s passed).
bool waitForVersion(const MapMirror& mirror, uint64_t version) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < give_up) {
    if (mirror.isSynced() && mirror.sequence() >= version) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

size_t differences(const std::map<VoxelKey, VoxelState>& a, const std::map<VoxelKey, VoxelState>& b) {
  size_t n = 0;
  for (const auto& [key, state] : a) {
    const auto it = b.find(key);
    n += it == b.end() || it->second != state;
  }
  for (const auto& [key, state] : b) n += a.find(key) == a.end();
  return n;
}

// Four views of the room corner: walls at x = 40 and y = 30 voxels, from moving origins.
std::vector<PointBatch> sceneBatches() {
  std::vector<PointBatch> batches;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d origin = centre(2 * i, -3 * i, i);
    batches.push_back(wallBatch(kWallX, origin, 0.1 * i));
    PointBatch side;
    side.origin_m = origin;
    side.timestamp_s = 0.1 * i + 0.05;
    for (int x = 0; x < 40; ++x) {
      for (int z = -10; z < 10; ++z) side.points_m.push_back(centre(x, 30, z));
    }
    batches.push_back(side);
  }
  return batches;
}

TEST(MapClientUpdates, MirrorFromTheUpdateStreamEqualsTheMapForLiveAndLateSubscribers) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient map(server.target());
  MapMirror live;
  auto subscription = map.subscribe({}, [&](const MapUpdate& u) { live.apply(u); });
  ASSERT_TRUE(waitForVersion(live, 0)) << "no initial snapshot of the empty map";
  EXPECT_EQ(live.numBlocks(), 0u);

  uint64_t version = 0;
  for (const PointBatch& batch : sceneBatches()) version = map.integratePoints(batch).map_version;
  ASSERT_TRUE(waitForVersion(live, version)) << "mirror at " << live.sequence() << ", map at " << version;
  const auto after_integration = serverVoxels(map);
  ASSERT_GT(after_integration.size(), 1000u);
  EXPECT_EQ(differences(mirrorVoxels(live), after_integration), 0u);
  EXPECT_EQ(live.stateAt(centre(kWallX, 0, 0)), VoxelState::kOccupied);

  // Clearing sends the cleared blocks (all unknown ones dropped from the mirror).
  version = map.clearBox({{1.0, -0.5, -0.5}, {2.5, 0.5, 0.5}}).map_version;
  ASSERT_TRUE(waitForVersion(live, version));
  const auto after_clear = serverVoxels(map);
  EXPECT_LT(after_clear.size(), after_integration.size());
  EXPECT_EQ(differences(mirrorVoxels(live), after_clear), 0u);
  EXPECT_EQ(live.stateAt(centre(kWallX, 0, 0)), VoxelState::kUnknown);

  // A late subscriber gets the whole map first.
  MapMirror late;
  auto late_subscription = map.subscribe({}, [&](const MapUpdate& u) { late.apply(u); });
  ASSERT_TRUE(waitForVersion(late, version));
  EXPECT_EQ(differences(mirrorVoxels(late), after_clear), 0u);
  EXPECT_EQ(late.occupied(), live.occupied());
  EXPECT_EQ(late.free(), live.free());
  EXPECT_GE(map.stats().subscribers, 2u);
  subscription->cancel();
  late_subscription->cancel();
  EXPECT_FALSE(subscription->isActive());
  EXPECT_GT(subscription->updatesReceived(), 8u);
}

TEST(MapClientUpdates, RegionSubscriberGetsOnlyBlocksTouchingItsRegion) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient map(server.target());
  const Box region{{1.9, -0.2, -0.2}, {2.2, 0.2, 0.2}};
  MapMirror mirror;
  std::atomic<int> outside{0};
  auto subscription = map.subscribe({region, false}, [&](const MapUpdate& u) {
    for (const UpdateBlock& b : u.blocks) {
      // Block faces in metres: 8 voxels a side.
      const Eigen::Vector3d lo = b.index.cast<double>() * 8 * kVoxel_m, hi = lo.array() + 8 * kVoxel_m;
      outside += (hi.array() < region.min_m.array()).any() || (lo.array() > region.max_m.array()).any();
    }
    mirror.apply(u);
  });
  for (const PointBatch& batch : sceneBatches()) map.integratePoints(batch);
  // Changes outside the region send nothing: end with one that touches it, and wait for that.
  const uint64_t version = map.integratePoints(wallBatch()).map_version;
  ASSERT_TRUE(waitForVersion(mirror, version)) << "mirror at " << mirror.sequence() << ", map at " << version;
  EXPECT_EQ(outside.load(), 0);
  EXPECT_EQ(mirror.stateAt(centre(kWallX, 0, 0)), VoxelState::kOccupied);
  EXPECT_EQ(mirror.stateAt(centre(kWallX, 15, 15)), VoxelState::kUnknown);  // outside: never sent
  EXPECT_GT(mirror.numBlocks(), 0u);
}

TEST(MapClientUpdates, SlowSubscriberIsResyncedAndEndsEqualToTheMap) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient map(server.target());
  MapMirror mirror;
  std::mutex gate;
  std::unique_lock hold(gate);  // the callback blocks until the map has moved far ahead
  std::atomic<int> resyncs{0};
  auto subscription = map.subscribe({}, [&](const MapUpdate& u) {
    std::lock_guard wait(gate);
    resyncs += u.resync;
    mirror.apply(u);
  });
  uint64_t version = 0;
  for (int i = 0; i < 200; ++i) {
    version =
        map.integratePoints(wallBatch(kWallX - (i % 20), centre(i % 7, (i % 5) - 2, (i % 3) - 1), 0.01 * i)).map_version;
  }
  hold.unlock();
  ASSERT_TRUE(waitForVersion(mirror, version)) << "mirror at " << mirror.sequence() << ", map at " << version;
  EXPECT_GT(resyncs.load(), 0) << "200 changes behind a blocked subscriber brought no resync";
  EXPECT_EQ(differences(mirrorVoxels(mirror), serverVoxels(map)), 0u);
}

TEST(MapClientUpdates, PointStreamRejectsABadBatchInItsAckAndGoesOn) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient map(server.target());
  std::vector<PointBatch> batches = sceneBatches();
  batches[2].points_m[5].x() = std::numeric_limits<double>::quiet_NaN();
  const auto acks = map.streamPoints(batches);
  ASSERT_EQ(acks.size(), batches.size());
  mapping::OccupancyMap reference{mapping::MapConfig{}};
  for (size_t i = 0; i < acks.size(); ++i) {
    EXPECT_EQ(acks[i].sequence, i);
    if (i == 2) {
      EXPECT_EQ(acks[i].status_code, static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT)) << acks[i].message;
      EXPECT_FALSE(acks[i].message.empty());
    } else {
      EXPECT_TRUE(acks[i].ok()) << "batch " << i << ": " << acks[i].message;
      EXPECT_GT(acks[i].voxels_updated, 0u);
      reference.integrate(toMappingBatch(batches[i]));
    }
  }
  // The map is the other batches' map, voxel for voxel.
  const auto got = serverVoxels(map);
  auto acc = reference.constAccessor();
  size_t mismatches = 0;
  for (const auto& [key, state] : got) {
    const auto [i, j, k] = key;
    mismatches += static_cast<int>(acc.state(Eigen::Vector3i(i, j, k))) != static_cast<int>(state);
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(got.size(), reference.stats().occupied + reference.stats().free);
  EXPECT_EQ(map.stats().batches_integrated, batches.size() - 1);
}

TEST(MapClientUpdates, PoseStreamAcksEachPoseAndFrameStreamNeedsACalibration) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient map(server.target());
  auto poses = map.openPosesStream();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<PoseStamped> sent(4);
  for (size_t i = 0; i < sent.size(); ++i) {
    sent[i].timestamp_s = 1.0 + 0.1 * static_cast<double>(i);
    sent[i].T_world_cam.position_m = Eigen::Vector3d(0.1 * static_cast<double>(i), 0, 0);
  }
  sent[1].T_world_cam.position_m.y() = nan;  // NaN: rejected
  sent[3].timestamp_s = 0.5;                 // out of order: rejected
  std::vector<PoseAck> acks;
  for (const PoseStamped& pose : sent) {
    ASSERT_TRUE(poses->write(pose));
    PoseAck ack;
    ASSERT_TRUE(poses->read(ack));
    acks.push_back(ack);
  }
  poses->finish();
  EXPECT_TRUE(acks[0].ok()) << acks[0].message;
  EXPECT_EQ(acks[1].status_code, static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT)) << acks[1].message;
  EXPECT_TRUE(acks[2].ok()) << acks[2].message;
  EXPECT_NE(acks[3].status_code, 0) << "an out-of-order pose was stored";
  EXPECT_EQ(map.stats().poses_received, 2u);  // the poses stored (the pose buffer counts accepted ones)

  // This server has no stereo rig (--calibration): the frame stream fails as a whole.
  auto frames = map.openFramesStream();
  StereoFrame frame;
  frame.timestamp_s = 1.0;
  frame.left.width = frame.right.width = 4;
  frame.left.height = frame.right.height = 2;
  frame.left.encoding = frame.right.encoding = ImageEncoding::kMono8;
  frame.left.raw = frame.right.raw = std::string(8, '\x80');
  frames->write(frame);
  try {
    frames->finish();
    ADD_FAILURE() << "a frame stream without calibration succeeded";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::FAILED_PRECONDITION) << e.what();
  }
}

TEST(MapClientUpdates, AdminEditsAndSnapshots) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient map(server.target());
  for (const PointBatch& batch : sceneBatches()) map.integratePoints(batch);
  mapping::OccupancyMap reference{mapping::MapConfig{}};
  for (const PointBatch& batch : sceneBatches()) reference.integrate(toMappingBatch(batch));
  // Premise: the maps compared below are not both empty.
  ASSERT_GT(reference.stats().occupied, 0u);
  ASSERT_GT(reference.stats().free, 0u);

  // Server-side snapshot, and the same map streamed to a local file: both load back exactly.
  const SnapshotResult written = map.snapshot("scene.vdb");
  EXPECT_GT(written.bytes, 0u);
  EXPECT_TRUE(std::filesystem::exists(server.snapshotDirectory() + "/scene.vdb")) << written.path;
  const std::string local = server.directory() + "/downloaded.vdb";
  const uint64_t bytes = map.downloadSnapshot(local);
  EXPECT_EQ(bytes, std::filesystem::file_size(local));
  for (const std::string& path : {server.snapshotDirectory() + "/scene.vdb", local}) {
    const auto loaded = mapping::loadMap(path);
    EXPECT_EQ(loaded->stats().occupied, reference.stats().occupied) << path;
    EXPECT_EQ(loaded->stats().free, reference.stats().free) << path;
  }
  EXPECT_NO_THROW(map.snapshot("scene.bt"));
  // Not only no error: the file is there and holds the map.
  ASSERT_TRUE(std::filesystem::exists(server.snapshotDirectory() + "/scene.bt"));
  EXPECT_EQ(mapping::loadMap(server.snapshotDirectory() + "/scene.bt")->stats().occupied, reference.stats().occupied);
  // The format follows the extension (mapping/io/map_file_format.h): a download named .bt is an
  // OctoMap tree, not a VDB under that name (issue 14).
  const std::string local_bt = server.directory() + "/downloaded.bt";
  map.downloadSnapshot(local_bt);
  std::string first_line;
  std::getline(std::ifstream(local_bt), first_line);
  EXPECT_EQ(first_line, "# Octomap OcTree binary file");
  EXPECT_EQ(mapping::loadMap(local_bt)->stats().occupied, reference.stats().occupied);
  for (const auto& [path, format] :
       {std::pair{"refused.vdb", SnapshotFormat::kPointsPly}, std::pair{"mesh.ply", SnapshotFormat::kFromExtension},
        std::pair{"scene.xyz", SnapshotFormat::kFromExtension}}) {
    try {
      map.snapshot(path, format);
      ADD_FAILURE() << path << " was written";
    } catch (const RpcError& e) {
      EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT) << e.what();
      EXPECT_EQ(e.message().rfind(std::string(path) + ": ", 0), 0u) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(server.snapshotDirectory() + "/" + path)) << path;
  }
  try {
    map.snapshot("../escape.vdb");
    ADD_FAILURE() << "a snapshot path with .. was accepted";
  } catch (const RpcError& e) {
    // server/host/snapshotter.h: a path outside the snapshot directory is refused.
    EXPECT_EQ(e.code(), grpc::StatusCode::PERMISSION_DENIED) << e.what();
  }

  // Clear box: every voxel of the box unknown, the rest untouched.
  const Box wall_part{{1.9, -0.3, -0.3}, {2.2, 0.3, 0.3}};
  const BoxCounts outside_before = map.boxes({{{-0.5, -1.2, -1.2}, {1.5, 1.2, 1.2}}})[0];
  EXPECT_GT(outside_before.free, 0u);                 // premise: "untouched" compares something
  EXPECT_GT(map.boxes({wall_part})[0].occupied, 0u);  // premise: the box had something to clear
  EXPECT_GT(map.clearBox(wall_part).changed_blocks, 0u);
  const BoxCounts cleared = map.boxes({wall_part})[0];
  EXPECT_EQ(cleared.occupied + cleared.free, 0u);
  const BoxCounts outside_after = map.boxes({{{-0.5, -1.2, -1.2}, {1.5, 1.2, 1.2}}})[0];
  EXPECT_EQ(outside_after.free, outside_before.free);
  // Clear sphere, as in-process.
  reference.clearBox(mapping::Aabb{wall_part.min_m, wall_part.max_m});
  map.clearSphere(centre(20, 0, 0), 0.3);
  reference.clearSphere(centre(20, 0, 0), 0.3);
  EXPECT_EQ(map.info().free, reference.stats().free);
  // Crop: nothing known farther than 1 m from the origin.
  EXPECT_GT(map.info().occupied, 0u);  // premise: the walls beyond 1 m are still there to crop
  map.crop(kOrigin_m, 1.0);
  reference.cropToRadius(kOrigin_m, 1.0);
  const MapInfo cropped = map.info();
  EXPECT_EQ(cropped.free, reference.stats().free);
  EXPECT_EQ(cropped.occupied, 0u);
  EXPECT_GT(cropped.free, 0u);  // premise of the reset below: the map is not empty yet
  EXPECT_LE(cropped.bounds.max_m.x(), 1.0 + 2 * kVoxel_m);
  // Reset: an empty map.
  map.reset();
  const MapInfo empty = map.info();
  EXPECT_EQ(empty.occupied + empty.free, 0u);
  EXPECT_TRUE(empty.bounds.isEmpty());
  EXPECT_EQ(map.voxel(centre(10, 0, 0)).state, VoxelState::kUnknown);
  EXPECT_EQ(server.stop(), 0) << server.log();
  EXPECT_TRUE(std::filesystem::exists(server.snapshotDirectory() + "/map.vdb")) << "no shutdown snapshot";
}

TEST(MapClientUpdates, EightQueryClientsDuringIngestSeeNoErrors) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  MapClient ingest(server.target());
  ingest.integratePoints(wallBatch());
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> calls{0}, errors{0}, wrong{0};
  std::string first_error;
  std::mutex error_mutex;
  std::vector<std::thread> clients;
  for (int c = 0; c < 8; ++c) {
    clients.emplace_back([&, c] {
      ClientOptions options;
      options.own_connection = true;
      MapClient map(server.target(), options);
      for (uint64_t n = 0; !stop; ++n) {
        try {
          switch ((n + c) % 4) {
            case 0: {
              // The wall is re-hit by every batch: it stays occupied whatever the reader sees.
              wrong += map.voxel(centre(kWallX, c, 0)).state != VoxelState::kOccupied;
              break;
            }
            case 1: wrong += !map.segment({centre(5, 0, 0), centre(60, 0, 0), 0.0}).hit; break;
            case 2: map.boxes({{{0, -0.5, -0.5}, {2.5, 0.5, 0.5}}}); break;
            case 3: map.distances({centre(30, c, 0)}); break;
          }
          ++calls;
        } catch (const std::exception& e) {
          std::lock_guard lock(error_mutex);
          if (errors++ == 0) first_error = e.what();
        }
      }
    });
  }
  // 15 Hz ingest of wall views from moving origins for 3 s.
  for (int frame = 0; frame < 45; ++frame) {
    const auto started = std::chrono::steady_clock::now();
    const Eigen::Vector3d origin = centre(frame % 10, (frame % 7) - 3, (frame % 5) - 2);
    EXPECT_TRUE(ingest.integratePoints(wallBatch(kWallX, origin, frame / 15.0)).ok());
    std::this_thread::sleep_until(started + std::chrono::microseconds(66667));
  }
  stop = true;
  for (auto& t : clients) t.join();
  EXPECT_EQ(errors.load(), 0u) << first_error;
  EXPECT_EQ(wrong.load(), 0u);
  EXPECT_GT(calls.load(), 8u * 10u);
  EXPECT_EQ(ingest.stats().batches_integrated, 46u);
}

}  // namespace
}  // namespace cenote::client::test
