// rpc_error.h: the exception every failed call of the C++ client throws: the gRPC status code, its
// name ("UNAUTHENTICATED") and the server's message, e.g.
//   "RESOURCE_EXHAUSTED: 100001 points in one request; server.max_batch is 100000"
// Threads: a plain value.
#pragma once

#include <grpcpp/support/status_code_enum.h>

#include <stdexcept>
#include <string>

namespace cenote::client {

class RpcError : public std::runtime_error {
 public:
  RpcError(grpc::StatusCode code, const std::string& message);

  grpc::StatusCode code() const { return code_; }
  // "UNAUTHENTICATED", "INVALID_ARGUMENT", ... as gRPC spells them.
  const char* codeName() const { return statusCodeName(code_); }
  // The server's message alone (what() is "<CODE NAME>: <message>").
  const std::string& message() const { return message_; }

  static const char* statusCodeName(grpc::StatusCode code);

 private:
  grpc::StatusCode code_;
  std::string message_;
};

}  // namespace cenote::client
