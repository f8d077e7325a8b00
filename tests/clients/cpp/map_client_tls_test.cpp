// map_client_tls_test.cpp: the C++ client over TLS to a real cenote-server (a self-signed
// certificate for 127.0.0.1 made with the openssl command), with and without client certificates
// (mutual TLS): the right certificates connect; plaintext, a foreign root or a missing client
// certificate do not (UNAVAILABLE: the handshake fails before any call).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "clients/cpp/map_client.h"
#include "common/text_file.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/clients/cpp/wall_scene.h"

namespace cenote::client::test {
namespace {

class MapClientTlsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("openssl version >/dev/null 2>&1") != 0) GTEST_SKIP() << "no openssl command";
    std::string tmpl = (std::filesystem::temp_directory_path() / "cenote-tls-XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
    for (const char* name : {"server", "client", "other"}) {
      const std::string command = "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=" + std::string(name) +
                                  " -addext subjectAltName=IP:127.0.0.1,DNS:localhost -keyout " + dir_ + "/" + name +
                                  ".key -out " + dir_ + "/" + name + ".pem >/dev/null 2>&1";
      ASSERT_EQ(std::system(command.c_str()), 0) << command;
    }
  }
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }
  std::string pem(const std::string& name) const { return readFileBytes(dir_ + "/" + name + ".pem", "test certificate"); }
  std::string key(const std::string& name) const { return readFileBytes(dir_ + "/" + name + ".key", "test key"); }

  // A call that must fail before reaching the service.
  static void expectUnavailable(MapClient& map, const char* what) {
    try {
      map.info();
      ADD_FAILURE() << what << ": the call succeeded";
    } catch (const RpcError& e) {
      EXPECT_EQ(e.code(), grpc::StatusCode::UNAVAILABLE) << what << ": " << e.what();
    }
  }

  std::string dir_;
};

TEST_F(MapClientTlsTest, ConnectsWithTheServersRootOnly) {
  ServerProcess server(
      CENOTE_SERVER_BINARY,
      {.token = "", .extra_args = {"--tls-cert", dir_ + "/server.pem", "--tls-key", dir_ + "/server.key"}});
  ClientOptions tls;
  tls.use_tls = true;
  tls.tls_root_cert_pem = pem("server");
  tls.deadline_s = 5.0;
  MapClient map(server.target(), tls);
  EXPECT_TRUE(map.integratePoints(wallBatch()).ok());
  EXPECT_EQ(map.info().occupied, 1600u);

  ClientOptions plaintext;
  plaintext.deadline_s = 5.0;
  MapClient plain(server.target(), plaintext);
  expectUnavailable(plain, "plaintext to a TLS server");
  ClientOptions foreign = tls;
  foreign.tls_root_cert_pem = pem("other");
  MapClient untrusting(server.target(), foreign);
  expectUnavailable(untrusting, "a root the server's certificate does not chain to");
}

TEST_F(MapClientTlsTest, MutualTlsNeedsTheClientCertificate) {
  ServerProcess server(CENOTE_SERVER_BINARY,
                       {.token = "",
                        .extra_args = {"--tls-cert", dir_ + "/server.pem", "--tls-key", dir_ + "/server.key",
                                       "--tls-client-ca", dir_ + "/client.pem"}});
  ClientOptions mutual;
  mutual.use_tls = true;
  mutual.tls_root_cert_pem = pem("server");
  mutual.tls_client_cert_pem = pem("client");
  mutual.tls_client_key_pem = key("client");
  mutual.deadline_s = 5.0;
  MapClient map(server.target(), mutual);
  EXPECT_NEAR(map.info().voxel_size_m, kVoxel_m, 1e-12);

  ClientOptions anonymous = mutual;
  anonymous.tls_client_cert_pem.clear();
  anonymous.tls_client_key_pem.clear();
  MapClient no_certificate(server.target(), anonymous);
  expectUnavailable(no_certificate, "no client certificate");
  ClientOptions stranger = mutual;
  stranger.tls_client_cert_pem = pem("other");
  stranger.tls_client_key_pem = key("other");
  MapClient wrong_certificate(server.target(), stranger);
  expectUnavailable(wrong_certificate, "a client certificate of another CA");

  ClientOptions half = mutual;
  half.tls_client_key_pem.clear();
  EXPECT_THROW(MapClient(server.target(), half), std::invalid_argument);
}

}  // namespace
}  // namespace cenote::client::test
