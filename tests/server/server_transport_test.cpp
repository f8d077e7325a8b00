// End-to-end: the server's transport on a vehicle. SIGTERM cancels open streams (frames, poses,
// subscriptions) instead of waiting for them, then writes its snapshot and exits 0. Idle update
// subscribers cost no thread and never lock planners out; beyond server.limits.max_subscribers
// they are refused. A subscriber beyond its byte budget is resynced. Snapshot downloads are
// capped. A connection older than server.transport.max_connection_age_s, or without calls for
// max_connection_idle_s, is closed, and its client reconnects on its next call.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <fstream>

#include "cenote/v1/updates.grpc.pb.h"
#include "mapping/io/map_io.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;
using client::test::ServerProcessOptions;

constexpr int kWidth = 64, kHeight = 48;

// A rectified rig of kWidth x kHeight (OpenCV FileStorage, P1 / P2).
std::string writeRig(const fs::path& dir) {
  const std::string path = (dir / "rig.yaml").string();
  const double f = 50.0, cx = (kWidth - 1) / 2.0, cy = (kHeight - 1) / 2.0, b = 0.1;
  const auto matrix = [](std::initializer_list<double> d) {
    std::string s = "!!opencv-matrix\n  rows: 3\n  cols: 4\n  dt: d\n  data: [";
    for (double v : d) s += std::to_string(v) + ", ";
    return s.substr(0, s.size() - 2) + "]\n";
  };
  std::ofstream(path) << "%YAML:1.0\nimage_width: " << kWidth << "\nimage_height: " << kHeight
                      << "\nP1: " << matrix({f, 0, cx, 0, 0, f, cy, 0, 0, 0, 1, 0})
                      << "P2: " << matrix({f, 0, cx, -f * b, 0, f, cy, 0, 0, 0, 1, 0});
  return path;
}

v1::StereoFrame rawFrame(double t_s) {
  v1::StereoFrame frame;
  frame.set_timestamp_s(t_s);
  std::string pixels(kWidth * kHeight, '\0');
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<char>((i * 37) % 251);
  for (v1::Image* image : {frame.mutable_left(), frame.mutable_right()}) {
    v1::RawImage* raw = image->mutable_raw();
    raw->set_width(kWidth);
    raw->set_height(kHeight);
    raw->set_encoding(v1::IMAGE_ENCODING_MONO8);
    raw->set_data(pixels);
  }
  frame.mutable_pose()->mutable_orientation()->set_w(1.0);
  return frame;
}

void integrate(Stubs& stubs, const v1::PointBatch& batch, v1::BatchAck* ack = nullptr) {
  auto context = contextWithDeadline();
  v1::BatchAck local;
  const grpc::Status status = stubs.ingest->IntegratePoints(context.get(), batch, ack ? ack : &local);
  ASSERT_TRUE(status.ok()) << status.error_message();
}

bool cancelledOrUnavailable(const grpc::Status& s) {
  return s.error_code() == grpc::StatusCode::CANCELLED || s.error_code() == grpc::StatusCode::UNAVAILABLE;
}

TEST(ServerShutdown, SigtermCancelsOpenStreamsThenWritesTheSnapshotAndExitsZero) {
  const fs::path dir = scratchDir("transport", "sigterm");
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--calibration", writeRig(dir)}});
  Stubs stubs(server.target());
  integrate(stubs, wallBatch(2.0, 1.0, 0.02, 1.0));
  const std::unique_ptr<mapping::OccupancyMap> served = downloadMap(*stubs.admin, dir.string());

  // A subscriber that has its snapshot and waits for changes.
  auto updates = v1::Updates::NewStub(stubs.channel);
  grpc::ClientContext subscribe_context;
  auto subscription = updates->Subscribe(&subscribe_context, v1::SubscribeRequest());
  v1::MapUpdate update;
  ASSERT_TRUE(subscription->Read(&update));
  EXPECT_TRUE(update.snapshot());
  // A frame stream whose first frame was acknowledged, left open.
  grpc::ClientContext frames_context;
  auto frames = stubs.ingest->StreamFrames(&frames_context);
  ASSERT_TRUE(frames->Write(rawFrame(1.0)));
  v1::FrameAck ack;
  ASSERT_TRUE(frames->Read(&ack));
  EXPECT_EQ(ack.outcome(), v1::FRAME_OUTCOME_PROCESSED) << ack.message();
  // A pose stream, left open.
  grpc::ClientContext poses_context;
  auto poses = stubs.ingest->StreamPoses(&poses_context);
  v1::PoseStamped pose;
  pose.set_timestamp_s(0.5);
  pose.mutable_pose()->mutable_orientation()->set_w(1.0);
  ASSERT_TRUE(poses->Write(pose));
  v1::PoseAck pose_ack;
  ASSERT_TRUE(poses->Read(&pose_ack));

  EXPECT_EQ(server.stop(), 0) << server.log();
  while (subscription->Read(&update)) {
  }
  const grpc::Status subscribe_status = subscription->Finish();
  EXPECT_EQ(subscribe_status.error_code(), grpc::StatusCode::UNAVAILABLE) << subscribe_status.error_message();
  while (frames->Read(&ack)) {
  }
  const grpc::Status frames_status = frames->Finish();
  EXPECT_TRUE(cancelledOrUnavailable(frames_status)) << frames_status.error_code() << " " << frames_status.error_message();
  while (poses->Read(&pose_ack)) {
  }
  const grpc::Status poses_status = poses->Finish();
  EXPECT_TRUE(cancelledOrUnavailable(poses_status)) << poses_status.error_code() << " " << poses_status.error_message();

  const std::string snapshot = server.snapshotDirectory() + "/map.vdb";
  ASSERT_TRUE(fs::exists(snapshot)) << server.log();
  const MapDifference diff = compareMaps(*served, *mapping::loadMap(snapshot));
  EXPECT_GT(diff.known, 20000u);
  EXPECT_EQ(diff.different_state, 0u);
  EXPECT_EQ(diff.different_log_odds, 0u);
  fs::remove_all(dir.parent_path());
}

// Opens `n` subscriptions on `channel` and reads each one's snapshot (so the server runs them all).
struct Subscribers {
  Subscribers(const std::shared_ptr<grpc::Channel>& channel, int n) : stub(v1::Updates::NewStub(channel)) {
    for (int i = 0; i < n; ++i) {
      contexts.push_back(std::make_unique<grpc::ClientContext>());
      readers.push_back(stub->Subscribe(contexts.back().get(), v1::SubscribeRequest()));
    }
    for (auto& reader : readers) {
      v1::MapUpdate update;
      if (reader->Read(&update) && update.snapshot_complete()) ++subscribed;
    }
  }
  ~Subscribers() {
    for (auto& context : contexts) context->TryCancel();
    for (auto& reader : readers) reader->Finish();
  }
  std::unique_ptr<v1::Updates::Stub> stub;
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReader<v1::MapUpdate>>> readers;
  int subscribed = 0;
};

TEST(ServerSubscribers, EightHundredIdleSubscribersHoldNoThreadsAndLockNoPlannerOut) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  Stubs stubs(server.target());
  Subscribers idle(stubs.channel, 800);
  ASSERT_EQ(idle.subscribed, 800);
  // gRPC's sync server held one thread per subscriber (800 and more); now they wait in the change feed.
  EXPECT_LT(threadsOf(server.pid()).size(), 100u);

  v1::BatchAck ack;
  integrate(stubs, wallBatch(2.0, 1.0, 0.05, 1.0), &ack);
  EXPECT_GT(ack.changed_blocks(), 0u);
  auto context = contextWithDeadline();
  v1::MapInfo info;
  const grpc::Status status = stubs.query->GetMapInfo(context.get(), v1::MapInfoRequest(), &info);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(info.map_version(), ack.map_version());
  // Every subscriber is sent the change.
  int changed = 0;
  for (auto& reader : idle.readers) {
    v1::MapUpdate update;
    if (reader->Read(&update) && update.sequence() == ack.map_version() && !update.snapshot()) ++changed;
  }
  EXPECT_EQ(changed, 800);
  auto stats_context = contextWithDeadline();
  v1::Stats stats;
  ASSERT_TRUE(stubs.admin->GetStats(stats_context.get(), v1::StatsRequest(), &stats).ok());
  EXPECT_EQ(stats.subscribers(), 800u);
}

// A server started with `yaml` as its configuration, in a scratch folder of its own
// (scratchDir("transport", name)) that goes when the test ends.
struct ConfiguredServer {
  ConfiguredServer(const std::string& name, const std::string& yaml)
      : dir(scratchDir("transport", name)),
        server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", writeConfig(dir, yaml)}}),
        stubs(server.target()) {}
  ~ConfiguredServer() { fs::remove_all(dir.parent_path()); }
  const fs::path dir;
  ServerProcess server;
  Stubs stubs;
};

TEST(ServerSubscribers, BeyondTheLimitASubscriberIsRefusedNamingIt) {
  ConfiguredServer s("max-subscribers", "server:\n  limits:\n    max_subscribers: 3\n");
  Subscribers three(s.stubs.channel, 3);
  ASSERT_EQ(three.subscribed, 3);
  Subscribers fourth(s.stubs.channel, 1);
  EXPECT_EQ(fourth.subscribed, 0);
  const grpc::Status status = fourth.readers[0]->Finish();
  fourth.readers.clear();
  fourth.contexts.clear();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(status.error_message(), "already 3 update subscribers: the limit server.limits.max_subscribers");
}

TEST(ServerSubscribers, AChangeBeyondTheByteBudgetIsSentAsAResync) {
  ConfiguredServer s("subscriber-bytes", "server:\n  max_subscriber_bytes: 4096\n");
  Subscribers one(s.stubs.channel, 1);
  ASSERT_EQ(one.subscribed, 1);
  v1::BatchAck ack;
  integrate(s.stubs, wallBatch(5.0, 3.0, 0.03, 1.0), &ack);
  ASSERT_GT(ack.changed_blocks() * 12, 4096u);  // the change's block indices exceed the budget
  v1::MapUpdate update;
  ASSERT_TRUE(one.readers[0]->Read(&update));
  EXPECT_TRUE(update.resync());
  EXPECT_TRUE(update.snapshot());
  EXPECT_EQ(update.sequence(), ack.map_version());
}

TEST(ServerStreams, BeyondTheLimitAPoseStreamIsRefusedAndPlannersKeepTheirThreads) {
  ConfiguredServer s("ingest-streams", "server:\n  limits:\n    max_ingest_streams: 3\n");
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReaderWriter<v1::PoseStamped, v1::PoseAck>>> streams;
  v1::PoseStamped pose;
  pose.mutable_pose()->mutable_orientation()->set_w(1.0);
  v1::PoseAck ack;
  for (int i = 0; i < 4; ++i) {
    contexts.push_back(contextWithDeadline());
    streams.push_back(s.stubs.ingest->StreamPoses(contexts.back().get()));
    pose.set_timestamp_s(i);
    streams.back()->Write(pose);
    EXPECT_EQ(streams.back()->Read(&ack), i < 3) << "stream " << i;
  }
  const grpc::Status refused = streams.back()->Finish();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(refused.error_message(),
            "already 3 pose and point streams running: the limit server.limits.max_ingest_streams");
  auto context = contextWithDeadline();
  v1::MapInfo info;
  EXPECT_TRUE(s.stubs.query->GetMapInfo(context.get(), v1::MapInfoRequest(), &info).ok());
  for (size_t i = 0; i + 1 < streams.size(); ++i) {
    streams[i]->WritesDone();
    EXPECT_TRUE(streams[i]->Finish().ok()) << "stream " << i;
  }
}

TEST(ServerSnapshots, ADownloadBeyondTheLimitIsRefusedNamingIt) {
  const fs::path dir = scratchDir("transport", "downloads");
  ServerProcess server(
      CENOTE_SERVER_BINARY,
      {.extra_args = {"--config", writeConfig(dir, "server:\n  limits:\n    max_snapshot_downloads: 1\n")}});
  Stubs stubs(server.target());
  for (int i = 0; i < 3; ++i) integrate(stubs, wallBatch(2.0 + i, 1.5 + i, 0.02, 1.0 + i));
  // A download of the mesh (the largest format) whose first 1 MiB chunk is read and the rest not,
  // over a channel that lets only 64 KiB more in (no BDP probing to widen it): gRPC's flow control
  // holds the server's handler in its writes.
  grpc::ChannelArguments narrow;
  narrow.SetInt(GRPC_ARG_HTTP2_BDP_PROBE, 0);
  narrow.SetInt(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, 64 << 10);
  auto slow = v1::Admin::NewStub(grpc::CreateCustomChannel(server.target(), grpc::InsecureChannelCredentials(), narrow));
  grpc::ClientContext held_context;
  v1::SnapshotRequest request;
  request.set_path("map.mesh.ply");
  auto held = slow->DownloadSnapshot(&held_context, request);
  v1::FileChunk chunk;
  ASSERT_TRUE(held->Read(&chunk));
  ASSERT_GT(chunk.total_bytes(), 2u << 20) << "the file must be more than two chunks for the test to hold";
  const uint64_t total = chunk.total_bytes();
  uint64_t received = chunk.data().size();

  auto context = contextWithDeadline();
  auto second = stubs.admin->DownloadSnapshot(context.get(), request);
  while (second->Read(&chunk)) {
  }
  const grpc::Status refused = second->Finish();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(refused.error_message(),
            "already 1 snapshot downloads running: the limit server.limits.max_snapshot_downloads");

  // The held download completes, and then the next one may start.
  while (held->Read(&chunk)) received += chunk.data().size();
  ASSERT_TRUE(held->Finish().ok());
  EXPECT_EQ(received, total);
  const auto map = downloadMap(*stubs.admin, dir.string());
  EXPECT_GT(map->stats().occupied, 0u);
  fs::remove_all(dir.parent_path());
}

// A server started with `yaml` as its --config (written into `dir`).
ServerProcess serverWithConfig(const fs::path& dir, const std::string& yaml) {
  return ServerProcess(CENOTE_SERVER_BINARY, ServerProcessOptions{.extra_args = {"--config", writeConfig(dir, yaml)}});
}

// Reads a stream to its end. @return how the server ended it.
template <typename Message, typename Stream>
grpc::Status endOf(Stream& stream) {
  Message message;
  while (stream.Read(&message)) {
  }
  return stream.Finish();
}

TEST(ServerConnections, StreamsOlderThanTheMaximumAgeEndUnavailableAndTheChannelReconnects) {
  const fs::path dir = scratchDir("transport", "max-age");
  const ServerProcess server = serverWithConfig(
      dir, "server:\n  transport:\n    max_connection_age_s: 1\n    max_connection_age_grace_s: 1\n");
  Stubs stubs(server.target());
  // Both kinds of stream, on one connection: an update subscription (gRPC's callback API) and a
  // pose stream (a thread of the sync server). The server sends GOAWAY after about 1 s (gRPC adds
  // +-10 % jitter) and closes the connection 1 s later; the deadlines only end a test whose server
  // never does.
  auto poses_context = contextWithDeadline(30.0);
  auto poses = stubs.ingest->StreamPoses(poses_context.get());
  v1::PoseStamped pose;  // t = 0, at the origin
  pose.mutable_pose()->mutable_orientation()->set_w(1.0);
  v1::PoseAck pose_ack;
  ASSERT_TRUE(poses->Write(pose) && poses->Read(&pose_ack));
  EXPECT_EQ(pose_ack.status_code(), 0) << pose_ack.message();
  auto updates = v1::Updates::NewStub(stubs.channel);
  auto subscribe_context = contextWithDeadline(30.0);
  auto subscription = updates->Subscribe(subscribe_context.get(), v1::SubscribeRequest());
  v1::MapUpdate update;
  ASSERT_TRUE(subscription->Read(&update));
  EXPECT_TRUE(update.snapshot_complete());

  const grpc::Status subscribe_status = endOf<v1::MapUpdate>(*subscription);
  EXPECT_EQ(subscribe_status.error_code(), grpc::StatusCode::UNAVAILABLE) << subscribe_status.error_message();
  const grpc::Status poses_status = endOf<v1::PoseAck>(*poses);
  EXPECT_EQ(poses_status.error_code(), grpc::StatusCode::UNAVAILABLE) << poses_status.error_message();

  // The next call on the same channel opens a new connection, and a new stream is served.
  v1::BatchAck ack;
  integrate(stubs, wallBatch(2.0, 0.5, 0.05, 1.0), &ack);
  EXPECT_GT(ack.map_version(), 0u);
  EXPECT_EQ(mapInfo(stubs).map_version(), ack.map_version());
  Subscribers again(stubs.channel, 1);
  EXPECT_EQ(again.subscribed, 1);
  fs::remove_all(dir.parent_path());
}

TEST(ServerConnections, AConnectionWithoutCallsIsClosedAfterTheIdleTimeAndTheNextCallReconnects) {
  const fs::path dir = scratchDir("transport", "max-idle");
  const ServerProcess server = serverWithConfig(dir, "server:\n  transport:\n    max_connection_idle_s: 1\n");
  Stubs stubs(server.target());
  mapInfo(stubs);
  ASSERT_EQ(stubs.channel->GetState(false), GRPC_CHANNEL_READY);
  {
    // An open subscription is a call: its connection is not idle, however quiet. Three idle times
    // pass, and the subscriber still gets the next change over the same connection.
    Subscribers planner(stubs.channel, 1);
    ASSERT_EQ(planner.subscribed, 1);
    EXPECT_FALSE(
        stubs.channel->WaitForStateChange(GRPC_CHANNEL_READY, std::chrono::system_clock::now() + std::chrono::seconds(3)));
    v1::BatchAck ack;
    integrate(stubs, wallBatch(2.0, 0.5, 0.05, 1.0), &ack);
    v1::MapUpdate update;
    ASSERT_TRUE(planner.readers[0]->Read(&update));
    EXPECT_EQ(update.sequence(), ack.map_version());
  }
  // Without calls, the server closes the connection (GOAWAY) after 1 s and the channel goes from
  // READY to IDLE; the deadline only ends a test whose server never closes it.
  EXPECT_TRUE(
      stubs.channel->WaitForStateChange(GRPC_CHANNEL_READY, std::chrono::system_clock::now() + std::chrono::seconds(30)));
  EXPECT_EQ(stubs.channel->GetState(false), GRPC_CHANNEL_IDLE);
  // A planner's next call reconnects.
  EXPECT_GT(mapInfo(stubs).map_version(), 0u);
  EXPECT_EQ(stubs.channel->GetState(false), GRPC_CHANNEL_READY);
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace cenote::server::test
