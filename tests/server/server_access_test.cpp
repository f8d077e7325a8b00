// End-to-end: who may do what on a real server. The operator's token may call everything; the
// read-only token may query, subscribe and read statistics, and gets PERMISSION_DENIED for the
// rest (a planner cannot Reset the map); no token or a wrong one gets UNAUTHENTICATED. Listening
// beyond loopback without a token, or with one but without TLS, is refused at start-up unless
// --allow-insecure-remote says otherwise, and then it is logged.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cenote/v1/updates.grpc.pb.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/refused_start.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;
using client::test::ServerProcessOptions;

std::unique_ptr<grpc::ClientContext> withToken(const std::string& token) {
  auto context = contextWithDeadline();
  if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
  return context;
}

grpc::Status reset(Stubs& stubs, const std::string& token) {
  v1::ChangeReply reply;
  return stubs.admin->Reset(withToken(token).get(), v1::ResetRequest(), &reply);
}

uint64_t occupied(Stubs& stubs, const std::string& token) {
  v1::MapInfo info;
  const grpc::Status status = stubs.query->GetMapInfo(withToken(token).get(), v1::MapInfoRequest(), &info);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return info.occupied();
}

TEST(ServerAccess, EachTokenGetsItsCodeAndAPlannerCannotReset) {
  const fs::path dir = scratchDir("access", "roles");
  std::ofstream(dir / "planner") << "planner-secret\n";
  ServerProcess server(CENOTE_SERVER_BINARY,
                       {.token = "operator-secret", .extra_args = {"--read-token-file", (dir / "planner").string()}});
  Stubs stubs(server.target());
  v1::BatchAck ack;
  ASSERT_TRUE(stubs.ingest->IntegratePoints(withToken("operator-secret").get(), wallBatch(2.0, 1.0, 0.05, 1.0), &ack).ok());
  const uint64_t before = occupied(stubs, "planner-secret");
  EXPECT_GT(before, 0u);

  const grpc::Status none = reset(stubs, "");
  EXPECT_EQ(none.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(none.error_message(), "missing token: send metadata 'authorization: Bearer <token>'");
  const grpc::Status wrong = reset(stubs, "guess");
  EXPECT_EQ(wrong.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(wrong.error_message(), "wrong token");
  const grpc::Status planner = reset(stubs, "planner-secret");
  EXPECT_EQ(planner.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(planner.error_message(),
            "/cenote.v1.Admin/Reset needs the operator token; the read-only token may call Query, Updates and "
            "Admin/GetStats");
  EXPECT_EQ(occupied(stubs, "operator-secret"), before);  // nothing was reset

  // The planner's token may ingest nothing, but may subscribe and read statistics.
  EXPECT_EQ(
      stubs.ingest->IntegratePoints(withToken("planner-secret").get(), wallBatch(3.0, 1.0, 0.05, 2.0), &ack).error_code(),
      grpc::StatusCode::PERMISSION_DENIED);
  v1::Stats stats;
  EXPECT_TRUE(stubs.admin->GetStats(withToken("planner-secret").get(), v1::StatsRequest(), &stats).ok());
  auto updates = v1::Updates::NewStub(stubs.channel);
  auto subscribe_context = withToken("planner-secret");
  auto subscription = updates->Subscribe(subscribe_context.get(), v1::SubscribeRequest());
  v1::MapUpdate update;
  EXPECT_TRUE(subscription->Read(&update));
  EXPECT_TRUE(update.snapshot());
  subscribe_context->TryCancel();
  subscription->Finish();
  auto unauthenticated_context = withToken("");
  auto refused = updates->Subscribe(unauthenticated_context.get(), v1::SubscribeRequest());
  EXPECT_FALSE(refused->Read(&update));
  EXPECT_EQ(refused->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);

  EXPECT_TRUE(reset(stubs, "operator-secret").ok());
  EXPECT_EQ(occupied(stubs, "planner-secret"), 0u);
  fs::remove_all(dir.parent_path());
}

TEST(ServerAccess, ListeningBeyondLoopbackWithoutTokenOrTlsIsRefusedAtStartUp) {
  const fs::path dir = scratchDir("access", "exposure");
  std::ofstream(dir / "token") << "operator-secret\n";
  expectRefusedToStart(dir, "--listen 0.0.0.0:0 --snapshot-dir " + (dir / "snapshots").string(),
                       {"cenote-server: error: refusing to start: listening on 0.0.0.0:0 (beyond loopback) without a "
                        "token: anyone who reaches the port may feed, reset or download the map."});
  expectRefusedToStart(dir, "--listen 0.0.0.0:0 --token-file " + (dir / "token").string(),
                       {"cenote-server: error: refusing to start: listening on 0.0.0.0:0 (beyond loopback) with a "
                        "token but without TLS: the token crosses the network in clear text."});
  expectRefusedToStart(dir, "--listen 127.0.0.1:0 --read-token-file " + (dir / "token").string(),
                       {"server.read_token_file"});

  // Said explicitly, it runs, and says what it risks.
  ServerProcess server(CENOTE_SERVER_BINARY,
                       {.token = "", .listen = "0.0.0.0:0", .extra_args = {"--allow-insecure-remote"}});
  EXPECT_NE(server.log().find("cenote-server: WARNING: listening on 0.0.0.0:0 (beyond loopback) without a token"),
            std::string::npos)
      << server.log();
  Stubs stubs(server.target());
  EXPECT_GE(occupied(stubs, ""), 0u);
  EXPECT_EQ(server.stop(), 0);
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace cenote::server::test
