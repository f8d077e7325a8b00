// call_guard.h: what every call of every cenote service goes through before and after its handler
// (the token and role were checked earlier, as the call's headers arrived: access_policy.h):
//  - the deadline: a call whose deadline has already passed gets DEADLINE_EXCEEDED unrun;
//  - errors: a StatusError keeps its code, a cenote::Error gets the code of its kind
//    (statusCodeOf in server/wire/status_error.h: bad input INVALID_ARGUMENT, a failed write
//    INTERNAL, a full disk RESOURCE_EXHAUSTED, ...), anything else INTERNAL; the message always says what;
//  - statistics: calls, errors and latency percentiles per method (Admin.GetStats);
//  - shutdown: streams run with runStream() are cancelled by cancelStreams() (the client sees
//    CANCELLED), so that an open stream never holds up a restart.
// Threads: run(), runStream() and cancelStreams() from any number of threads at once.
#pragma once

#include <grpcpp/server_context.h>

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/stage_timer.h"
#include "server/wire/status_error.h"

namespace cenote::server {

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
  // Runs `handler` (returning grpc::Status) for the call named `method` ("Query/GetVoxels").
  // Context: grpc::ServerContext, or grpc::CallbackServerContext (the handler then only sets the
  // call up: Updates.Subscribe).
  template <typename Context, typename Handler>
  grpc::Status run(Context* context, const char* method, Handler&& handler) {
    const auto start = std::chrono::steady_clock::now();
    grpc::Status status;
    if (context->deadline() < std::chrono::system_clock::now()) {
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

  // run() for a long-lived stream (StreamFrames, StreamPoses, StreamPoints): cancelStreams()
  // cancels it, and its handler then sees the stream end (Read() false) and returns.
  template <typename Handler>
  grpc::Status runStream(grpc::ServerContext* context, const char* method, Handler&& handler) {
    struct Registered {
      CallGuard& guard;
      grpc::ServerContext* context;
      ~Registered() { guard.removeStream(context); }
    } registered{*this, context};
    addStream(context);
    return run(context, method, std::forward<Handler>(handler));
  }

  // Cancels every stream running now and every one that starts later (server shutdown).
  void cancelStreams();

  std::vector<MethodSummary> summaries() const;

 private:
  MethodStats& stats(const char* method);
  void addStream(grpc::ServerContext* context);
  void removeStream(grpc::ServerContext* context);

  mutable std::mutex mutex_;
  std::map<std::string, std::unique_ptr<MethodStats>> stats_;
  std::mutex streams_mutex_;
  std::set<grpc::ServerContext*> streams_;
  bool streams_cancelled_ = false;
};

}  // namespace cenote::server
