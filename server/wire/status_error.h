// status_error.h: an error that carries the gRPC status it must be reported with. Server code
// throws it where the code matters (limits: RESOURCE_EXHAUSTED, bad input: INVALID_ARGUMENT);
// call_guard.h turns it, and every other exception, into the call's status.
// Threads: a plain value.
#pragma once

#include <grpcpp/support/status.h>

#include <stdexcept>
#include <string>

namespace cenote::server {

class StatusError : public std::runtime_error {
 public:
  StatusError(grpc::StatusCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }
  grpc::Status status() const { return grpc::Status(code_, what()); }

 private:
  grpc::StatusCode code_;
};

inline StatusError invalidArgument(const std::string& message) {
  return StatusError(grpc::StatusCode::INVALID_ARGUMENT, message);
}
inline StatusError resourceExhausted(const std::string& message) {
  return StatusError(grpc::StatusCode::RESOURCE_EXHAUSTED, message);
}

}  // namespace cenote::server
