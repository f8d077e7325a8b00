// call_guard.h: what every call of every cenote service goes through before and after its handler:
//  - the bearer token (metadata `authorization: Bearer <token>`), checked first: a missing or wrong
//    token gets UNAUTHENTICATED and the handler never runs, so nothing is touched;
//  - the deadline: a call whose deadline has already passed gets DEADLINE_EXCEEDED unrun;
//  - errors: a StatusError keeps its code, a cenote::Error gets the code of its kind
//    (statusCodeOf in server/wire/status_error.h: bad input INVALID_ARGUMENT, a failed write
//    INTERNAL, a full disk RESOURCE_EXHAUSTED, ...), anything else INTERNAL; the message always says what;
//  - statistics: calls, errors and latency percentiles per method (Admin.GetStats).
// Threads: run() from any number of handler threads at once.
#pragma once

#include <grpcpp/server_context.h>

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/stage_timer.h"
#include "server/wire/status_error.h"

namespace cenote::server {

class Authenticator {
 public:
  // Empty token: every call is let in.
  explicit Authenticator(std::string token) : token_(std::move(token)) {}
  grpc::Status check(const grpc::ServerContext& context) const;
  bool enabled() const { return !token_.empty(); }

 private:
  std::string token_;
};

struct MethodSummary {
  std::string method;
  uint64_t calls = 0;
  uint64_t errors = 0;
  double p50_ms = 0.0;
  double p99_ms = 0.0;
};

// Latencies of one method (the most recent StageTimer::kMaxSamples, for percentiles) and counts.
class MethodStats {
 public:
  void record(double ms, bool ok);
  MethodSummary summary(const std::string& method) const;

 private:
  mutable std::mutex mutex_;
  StageTimer latency_;
  uint64_t errors_ = 0;
};

class CallGuard {
 public:
  explicit CallGuard(Authenticator auth) : auth_(std::move(auth)) {}

  // Runs `handler` (returning grpc::Status) for the call named `method` ("Query/GetVoxels").
  template <typename Handler>
  grpc::Status run(grpc::ServerContext* context, const char* method, Handler&& handler) {
    const auto start = std::chrono::steady_clock::now();
    grpc::Status status = auth_.check(*context);
    if (status.ok() && context->deadline() < std::chrono::system_clock::now()) {
      status = grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                            std::string(method) + ": deadline passed before the call ran");
    }
    if (status.ok()) {
      try {
        status = handler();
      } catch (const StatusError& e) {
        status = e.status();
      } catch (const Error& e) {
        status = toStatusError(e).status();
      } catch (const std::exception& e) {
        status = grpc::Status(grpc::StatusCode::INTERNAL, std::string(method) + ": " + e.what());
      }
    }
    stats(method).record(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count(),
                         status.ok());
    return status;
  }

  std::vector<MethodSummary> summaries() const;
  const Authenticator& auth() const { return auth_; }

 private:
  MethodStats& stats(const char* method);

  Authenticator auth_;
  mutable std::mutex mutex_;
  std::map<std::string, std::unique_ptr<MethodStats>> stats_;
};

}  // namespace cenote::server
