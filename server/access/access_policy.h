// access_policy.h: who may call what. Two bearer tokens (metadata `authorization: Bearer <token>`):
//  - the operator token may call everything;
//  - the read-only token (a planner's, a viewer's) may call Query.*, Updates.* and Admin.GetStats,
//    and gets PERMISSION_DENIED for Ingest.* and the rest of Admin (Snapshot, Reset, ClearBox, ...).
// A call of a cenote service (path /cenote.v1.*) without a token, or with one that is neither, gets
// UNAUTHENTICATED; gRPC's health and reflection services stay open, as probes expect.
// The check runs in gRPC's transport when a call's headers arrive (serverCredentials, below: the
// server's auth filter), before its request message is parsed and before a handler or thread is
// given to it: a stranger's 64 MiB message is never decoded.
// Threads: check() from any number of gRPC threads at once (the policy is immutable).
#pragma once

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/support/status.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace cenote::server {

enum class Role { kNone, kReader, kOperator };

// The role a method needs. path: gRPC's ":path", "/cenote.v1.Admin/Reset". kNone: anyone (not a
// cenote service); an empty path (none seen) needs the operator.
Role requiredRole(std::string_view path);

class AccessPolicy {
 public:
  // operator_token empty: every call is let in (reader_token must then be empty too).
  AccessPolicy(std::string operator_token, std::string reader_token);

  // OK, UNAUTHENTICATED (no token, a wrong token, or not "Bearer ...") or PERMISSION_DENIED (the
  // read-only token on an operator's method). authorization: the metadata's value, if sent.
  grpc::Status check(std::string_view path, std::optional<std::string_view> authorization) const;
  bool enabled() const { return !operator_token_.empty(); }

 private:
  std::string operator_token_, reader_token_;
};

// TLS files (PEM); all empty: plain text.
struct TlsFiles {
  std::string cert, key, client_ca;  // client_ca: mutual TLS, clients must present a certificate
};

// Whether `listen` (gRPC's HOST:PORT, or unix:PATH) is reachable only from this machine:
// 127.0.0.0/8, localhost, [::1], a unix socket.
bool isLoopbackOnly(const std::string& listen);

// Why listening on `listen` so would expose the map (beyond loopback without a token, or with a
// token but without TLS, which sends it in clear text); empty when it would not.
std::string exposureProblem(const std::string& listen, bool has_token, bool has_tls);

// The server's transport credentials (plain text or TLS from `tls`), with `policy` checked on every
// call as its headers arrive. @throws cenote::Error for a half-given TLS pair or unreadable files.
std::shared_ptr<grpc::ServerCredentials> serverCredentials(const TlsFiles& tls, std::shared_ptr<const AccessPolicy> policy);

}  // namespace cenote::server
