// The viewer's HTTP side in process, spoken to with plain sockets (no WebSocket library): the
// token and subprotocol checks of the upgrade, the page's files. The protocol itself is tested
// end to end by tests/viewer/ (Node's @foxglove/ws-protocol against cenote-server).
#include "server/viewer/viewer_server.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "common/error.h"

namespace cenote::server::viewer {
namespace {

// Sends `request` to 127.0.0.1:port and returns all the server answers until it closes (or 2 s).
std::string exchange(int port, const std::string& request) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval timeout{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  if (connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
    close(fd);
    return "connect failed";
  }
  send(fd, request.data(), request.size(), 0);
  std::string reply;
  char buffer[4096];
  for (ssize_t n; (n = recv(fd, buffer, sizeof(buffer), 0)) > 0;) reply.append(buffer, static_cast<size_t>(n));
  close(fd);
  return reply;
}

std::string upgrade(const std::string& target, const std::string& extra) {
  return "GET " + target +
         " HTTP/1.1\r\nHost: localhost\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
         "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n" +
         extra + "\r\n";
}

class ViewerServerHttp : public ::testing::Test {
 protected:
  void SetUp() override {
    web_ = std::filesystem::path(::testing::TempDir()) / "viewer-web";
    std::filesystem::create_directories(web_);
    std::ofstream(web_ / "index.html") << "<html>cenote</html>";
    ViewerConfig config;
    config.listen = "127.0.0.1:0";
    config.web_dir = web_.string();
    ViewerSources sources;
    sources.map = &map_;
    sources.tokens = {"s3cret", "r3ader"};  // cenote-server's operator and read-only tokens
    server_ = std::make_unique<ViewerServer>(config, std::move(sources));
  }
  std::filesystem::path web_;
  mapping::OccupancyMap map_{mapping::MapConfig{}};
  std::unique_ptr<ViewerServer> server_;
};

TEST_F(ViewerServerHttp, UpgradeWithoutTheTokenIs401) {
  const std::string reply = exchange(server_->port(), upgrade("/", "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n"));
  EXPECT_EQ(reply.rfind("HTTP/1.1 401", 0), 0u) << reply;
  EXPECT_NE(reply.find("missing or wrong token"), std::string::npos) << reply;
  EXPECT_EQ(exchange(server_->port(), upgrade("/?token=wrong", "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n"))
                .rfind("HTTP/1.1 401", 0),
            0u);
}

TEST_F(ViewerServerHttp, UpgradeWithEitherTokenInHeaderOrQuerySwitchesToTheFoxgloveSubprotocol) {
  for (const std::string& request :
       {upgrade("/?token=s3cret", "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n"),
        upgrade("/?token=r3ader", "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n"),
        upgrade("/", "Authorization: Bearer s3cret\r\nSec-WebSocket-Protocol: other, foxglove.websocket.v1\r\n")}) {
    const std::string reply = exchange(server_->port(), request);
    EXPECT_EQ(reply.rfind("HTTP/1.1 101", 0), 0u) << reply;
    EXPECT_NE(reply.find("Sec-WebSocket-Protocol: foxglove.websocket.v1"), std::string::npos) << reply;
    // The server speaks first: serverInfo, in a text frame (opcode 1, FIN).
    const size_t body = reply.find("\r\n\r\n");
    ASSERT_NE(body, std::string::npos);
    ASSERT_GT(reply.size(), body + 6);
    EXPECT_EQ(static_cast<unsigned char>(reply[body + 4]), 0x81u);
    EXPECT_NE(reply.find("\"op\":\"serverInfo\""), std::string::npos);
    EXPECT_NE(reply.find("\"op\":\"advertise\""), std::string::npos);
  }
}

TEST_F(ViewerServerHttp, UpgradeWithoutTheSubprotocolIs400NamingIt) {
  const std::string reply = exchange(server_->port(), upgrade("/?token=s3cret", ""));
  EXPECT_EQ(reply.rfind("HTTP/1.1 400", 0), 0u) << reply;
  EXPECT_NE(reply.find("WebSocket subprotocol foxglove.websocket.v1 required"), std::string::npos) << reply;
}

TEST_F(ViewerServerHttp, ServesThePageAndRefusesOtherPaths) {
  const std::string page = exchange(server_->port(), "GET / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(page.rfind("HTTP/1.1 200", 0), 0u) << page;
  EXPECT_NE(page.find("text/html"), std::string::npos);
  EXPECT_NE(page.find("<html>cenote</html>"), std::string::npos);
  const std::string escape = exchange(server_->port(), "GET /../secret HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(escape.rfind("HTTP/1.1 404", 0), 0u) << escape;
  const std::string post = exchange(server_->port(),
                                    "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(post.rfind("HTTP/1.1 405", 0), 0u) << post;
}

// A masked client text frame (RFC 6455 5.3), as a browser sends one.
std::string clientTextFrame(const std::string& text) {
  std::string frame = "\x81";
  frame += static_cast<char>(0x80 | text.size());  // under 126 bytes
  const char mask[4] = {0x12, 0x34, 0x56, 0x78};
  frame.append(mask, 4);
  for (size_t i = 0; i < text.size(); ++i) frame += static_cast<char>(text[i] ^ mask[i % 4]);
  return frame;
}

TEST(ViewerServer, AClientThatStopsReadingIsNotQueuedWithoutBound) {
  mapping::OccupancyMap map{mapping::MapConfig{}};
  PointBatch wall;  // 90000 occupied voxels: about 16 MB of cubes
  for (int j = -150; j < 150; ++j)
    for (int k = -150; k < 150; ++k) wall.points.emplace_back(3.0f, 0.05f * j + 0.025f, 0.05f * k + 0.025f);
  map.integrate(wall);
  ViewerConfig config;
  config.listen = "127.0.0.1:0";
  config.budget_bytes_per_s = 2.0e6;
  ViewerSources sources;
  sources.map = &map;
  ViewerServer server(config, sources);

  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  const int small = 4096;  // a slow link: the server's writes block soon
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(server.port()));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  const std::string request = upgrade("/", "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n");
  send(fd, request.data(), request.size(), 0);
  char head[512];  // the 101 response (and maybe serverInfo): as a client, wait for it, then subscribe
  ASSERT_GT(recv(fd, head, sizeof(head), 0), 12);
  ASSERT_EQ(std::string(head, 12), "HTTP/1.1 101");
  const std::string subscribe = clientTextFrame(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  send(fd, subscribe.data(), subscribe.size(), 0);
  // Never read. At 2 MB/s the whole map would be made within 8 s; instead the server makes what the
  // sockets take plus a second's worth, then nothing more.
  std::this_thread::sleep_for(std::chrono::seconds(4));
  const uint64_t after_4s = server.bytesSent();
  std::this_thread::sleep_for(std::chrono::seconds(4));
  const uint64_t after_8s = server.bytesSent();
  close(fd);
  EXPECT_GT(after_4s, 100000u);
  EXPECT_LT(after_8s, 9000000u) << "bytes made for a client that reads nothing";
  EXPECT_LT(after_8s - after_4s, 500000u) << "the server went on making bytes for a client that reads nothing";
}

TEST(ViewerServer, AnAddressInUseIsAnErrorNamingTheKey) {
  mapping::OccupancyMap map{mapping::MapConfig{}};
  ViewerConfig config;
  config.listen = "127.0.0.1:0";
  ViewerSources sources;
  sources.map = &map;
  ViewerServer first(config, sources);
  config.listen = "127.0.0.1:" + std::to_string(first.port());
  try {
    ViewerServer second(config, sources);
    FAIL() << "a second server listened on the same port";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("server.viewer.listen = " + config.listen + ": cannot listen: ", 0), 0u)
        << e.what();
  }
}

TEST(ViewerConfig, DefaultsAreValidAndBadValuesNameTheirKey) {
  EXPECT_TRUE(ViewerConfig{}.validate().empty());
  ViewerConfig bad;
  bad.listen = "nocolon";
  bad.budget_bytes_per_s = 10.0;
  bad.color_by = "depth";
  const std::vector<ConfigError> errors = bad.validate();
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_EQ(errors[0].toString(),
            "server.viewer.listen = nocolon: must be HOST:PORT (port 0 picks a free one), or empty for no viewer");
  EXPECT_EQ(errors[1].toString(), "server.viewer.budget_bytes_per_s = 10: must be in [1e4, 1e10]");
  EXPECT_EQ(errors[2].toString(), "server.viewer.color_by = depth: must be image or height");
}

}  // namespace
}  // namespace cenote::server::viewer
