// status_error.h: an error that carries the gRPC status it must be reported with. Server code
// throws it where the code matters (limits: RESOURCE_EXHAUSTED, bad input: INVALID_ARGUMENT);
// call_guard.h turns it, and every other exception, into the call's status.
// statusCodeOf() is the one place where a library error's kind (common/error.h) becomes a gRPC
// code (table in docs/SERVER.md, "Errors"):
//   kInvalidArgument -> INVALID_ARGUMENT     kNotFound -> NOT_FOUND
//   kResourceExhausted -> RESOURCE_EXHAUSTED (limits, a full disk)
//   kIoFailure -> INTERNAL (the server's disk failed; retrying the same call will not help)
//   kFailedPrecondition -> FAILED_PRECONDITION
// Threads: plain values and pure functions.
#pragma once

#include <grpcpp/support/status.h>

#include <stdexcept>
#include <string>

#include "common/error.h"

namespace cenote::server {

class StatusError : public std::runtime_error {
 public:
  StatusError(grpc::StatusCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }
  grpc::Status status() const { return grpc::Status(code_, what()); }

 private:
  grpc::StatusCode code_;
};

constexpr grpc::StatusCode statusCodeOf(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kInvalidArgument: return grpc::StatusCode::INVALID_ARGUMENT;
    case ErrorKind::kNotFound: return grpc::StatusCode::NOT_FOUND;
    case ErrorKind::kResourceExhausted: return grpc::StatusCode::RESOURCE_EXHAUSTED;
    case ErrorKind::kIoFailure: return grpc::StatusCode::INTERNAL;
    case ErrorKind::kFailedPrecondition: return grpc::StatusCode::FAILED_PRECONDITION;
  }
  return grpc::StatusCode::INTERNAL;
}

// The library error as the status it is reported with: the same message, the code of its kind.
inline StatusError toStatusError(const Error& e) { return StatusError(statusCodeOf(e.kind()), e.what()); }

inline StatusError invalidArgument(const std::string& message) {
  return StatusError(grpc::StatusCode::INVALID_ARGUMENT, message);
}
inline StatusError resourceExhausted(const std::string& message) {
  return StatusError(grpc::StatusCode::RESOURCE_EXHAUSTED, message);
}

}  // namespace cenote::server
