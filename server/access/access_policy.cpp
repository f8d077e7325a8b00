#include "server/access/access_policy.h"

#include <grpc/grpc.h>
#include <grpc/grpc_security.h>
#include <grpc/slice.h>

#include "common/error.h"
#include "common/text_file.h"

namespace cenote::server {
namespace {

constexpr std::string_view kCenotePrefix = "/cenote.";

// Compares in a time that does not depend on where the strings first differ (the token's length
// is not the secret).
bool equalConstantTime(std::string_view given, std::string_view token) {
  if (given.size() != token.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < given.size(); ++i) diff |= static_cast<unsigned char>(given[i] ^ token[i]);
  return diff == 0;
}

std::string_view view(const grpc_slice& slice) {
  return {reinterpret_cast<const char*>(GRPC_SLICE_START_PTR(slice)), GRPC_SLICE_LENGTH(slice)};
}

// gRPC core's hook, called by the server's auth filter with a call's initial metadata (":path"
// included), before the call's messages are read. The check is cheap, so it answers at once.
void processMetadata(void* state, grpc_auth_context*, const grpc_metadata* md, size_t num_md,
                     grpc_process_auth_metadata_done_cb done, void* user_data) {
  const auto& policy = *static_cast<const std::shared_ptr<const AccessPolicy>*>(state);
  std::string_view path;
  std::optional<std::string_view> authorization;
  for (size_t i = 0; i < num_md; ++i) {
    const std::string_view key = view(md[i].key);
    if (key == ":path") path = view(md[i].value);
    if (key == "authorization") authorization = view(md[i].value);
  }
  const grpc::Status status = policy->check(path, authorization);
  done(user_data, nullptr, 0, nullptr, 0, static_cast<grpc_status_code>(status.error_code()),
       status.ok() ? nullptr : status.error_message().c_str());
}

void destroyState(void* state) { delete static_cast<std::shared_ptr<const AccessPolicy>*>(state); }

// Transport credentials made from gRPC core's own (plain text or TLS) with the policy as their
// auth metadata processor. grpc::InsecureServerCredentials() refuses a processor (its
// SetAuthMetadataProcessor asserts), but core's insecure credentials run the auth filter like any
// other, so the same check covers plain text and TLS.
class CheckedServerCredentials final : public grpc::ServerCredentials {
 public:
  CheckedServerCredentials(grpc_server_credentials* creds, std::shared_ptr<const AccessPolicy> policy) : creds_(creds) {
    if (policy && policy->enabled()) {
      grpc_server_credentials_set_auth_metadata_processor(
          creds_, {processMetadata, destroyState, new std::shared_ptr<const AccessPolicy>(std::move(policy))});
    }
  }
  ~CheckedServerCredentials() override { grpc_server_credentials_release(creds_); }
  CheckedServerCredentials(const CheckedServerCredentials&) = delete;
  CheckedServerCredentials& operator=(const CheckedServerCredentials&) = delete;

  void SetAuthMetadataProcessor(const std::shared_ptr<grpc::AuthMetadataProcessor>&) override {
    throw Error("cenote-server: the access policy is set when the credentials are made");
  }

 private:
  int AddPortToServer(const std::string& addr, grpc_server* server) override {
    return grpc_server_add_http2_port(server, addr.c_str(), creds_);
  }

  grpc_server_credentials* creds_;
};

grpc_server_credentials* tlsCredentials(const TlsFiles& tls) {
  const std::string key = readFileBytes(tls.key, "TLS key");
  const std::string cert = readFileBytes(tls.cert, "TLS certificate");
  const std::string client_ca = tls.client_ca.empty() ? "" : readFileBytes(tls.client_ca, "TLS client CA");
  grpc_ssl_pem_key_cert_pair pair{key.c_str(), cert.c_str()};
  grpc_ssl_server_certificate_config* config = grpc_ssl_server_certificate_config_create(
      client_ca.empty() ? nullptr : client_ca.c_str(), &pair, 1);
  grpc_ssl_server_credentials_options* options = grpc_ssl_server_credentials_create_options_using_config(
      client_ca.empty() ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                        : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY,
      config);
  grpc_server_credentials* creds = grpc_ssl_server_credentials_create_with_options(options);  // takes options
  if (!creds) throw Error("TLS: gRPC refused the certificate " + tls.cert + " or key " + tls.key);
  return creds;
}

}  // namespace

Role requiredRole(std::string_view path) {
  if (path.empty()) return Role::kOperator;  // no :path seen: fail closed
  if (path.substr(0, kCenotePrefix.size()) != kCenotePrefix) return Role::kNone;
  for (std::string_view reader : {"/cenote.v1.Query/", "/cenote.v1.Updates/", "/cenote.v1.Admin/GetStats"}) {
    if (path.substr(0, reader.size()) == reader) return Role::kReader;
  }
  return Role::kOperator;  // Ingest, the rest of Admin, and any method added later
}

AccessPolicy::AccessPolicy(std::string operator_token, std::string reader_token)
    : operator_token_(std::move(operator_token)), reader_token_(std::move(reader_token)) {
  if (operator_token_.empty() && !reader_token_.empty()) {
    throw Error("a read-only token needs an operator token (server.token_file) as well");
  }
  if (!operator_token_.empty() && operator_token_ == reader_token_) {
    throw Error("the read-only token and the operator token are the same: give each role its own");
  }
}

grpc::Status AccessPolicy::check(std::string_view path, std::optional<std::string_view> authorization) const {
  const Role needed = requiredRole(path);
  if (!enabled() || needed == Role::kNone) return grpc::Status::OK;
  if (!authorization) {
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "missing token: send metadata 'authorization: Bearer <token>'");
  }
  constexpr std::string_view kBearer = "Bearer ";
  if (authorization->substr(0, kBearer.size()) != kBearer) {
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "wrong token: send 'authorization: Bearer <token>'");
  }
  const std::string_view token = authorization->substr(kBearer.size());
  // Both comparisons always run: the time does not say which token was close.
  const bool is_operator = equalConstantTime(token, operator_token_);
  const bool is_reader = !reader_token_.empty() && equalConstantTime(token, reader_token_);
  if (is_operator) return grpc::Status::OK;
  if (!is_reader) return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "wrong token");
  if (needed == Role::kReader) return grpc::Status::OK;
  return grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                      std::string(path) + " needs the operator token; the read-only token may call Query, Updates and "
                                          "Admin/GetStats");
}

bool isLoopbackOnly(const std::string& listen) {
  if (listen.rfind("unix:", 0) == 0 || listen.rfind("unix-abstract:", 0) == 0) return true;
  const size_t colon = listen.rfind(':');
  const std::string host = colon == std::string::npos ? listen : listen.substr(0, colon);
  return host == "localhost" || host == "[::1]" || host == "::1" || host.rfind("127.", 0) == 0;
}

std::string exposureProblem(const std::string& listen, bool has_token, bool has_tls) {
  if (isLoopbackOnly(listen)) return "";
  if (!has_token) {
    return "listening on " + listen +
           " (beyond loopback) without a token: anyone who reaches the port may feed, reset or "
           "download the map. Give --token-file (and --tls-cert/--tls-key), listen on 127.0.0.1, or pass "
           "--allow-insecure-remote to run so anyway";
  }
  if (!has_tls) {
    return "listening on " + listen +
           " (beyond loopback) with a token but without TLS: the token crosses the network in clear "
           "text. Give --tls-cert and --tls-key, listen on 127.0.0.1, or pass --allow-insecure-remote to run so "
           "anyway";
  }
  return "";
}

std::shared_ptr<grpc::ServerCredentials> serverCredentials(const TlsFiles& tls,
                                                           std::shared_ptr<const AccessPolicy> policy) {
  if (tls.cert.empty() && tls.key.empty()) {
    if (!tls.client_ca.empty()) throw Error("--tls-client-ca needs --tls-cert and --tls-key");
    return std::make_shared<CheckedServerCredentials>(grpc_insecure_server_credentials_create(), std::move(policy));
  }
  if (tls.cert.empty() || tls.key.empty()) throw Error("TLS needs both --tls-cert and --tls-key");
  return std::make_shared<CheckedServerCredentials>(tlsCredentials(tls), std::move(policy));
}

}  // namespace cenote::server
