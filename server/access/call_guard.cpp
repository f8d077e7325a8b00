#include "server/access/call_guard.h"

namespace cenote::server {

void MethodStats::record(double ms, bool ok) {
  std::lock_guard<std::mutex> lock(mutex_);
  latency_.add(ms);
  if (!ok) ++errors_;
}

MethodSummary MethodStats::summary(const std::string& method) const {
  std::lock_guard<std::mutex> lock(mutex_);
  MethodSummary s;
  s.method = method;
  s.calls = latency_.count();
  s.errors = errors_;
  s.p50_ms = latency_.percentile(0.5);
  s.p99_ms = latency_.percentile(0.99);
  return s;
}

MethodStats& CallGuard::stats(const char* method) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::unique_ptr<MethodStats>& slot = stats_[method];
  if (!slot) slot = std::make_unique<MethodStats>();
  return *slot;
}

std::vector<MethodSummary> CallGuard::summaries() const {
  std::vector<MethodSummary> out;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [name, stats] : stats_) out.push_back(stats->summary(name));
  return out;
}

void CallGuard::addStream(grpc::ServerContext* context) {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  streams_.insert(context);
  if (streams_cancelled_) context->TryCancel();
}

void CallGuard::removeStream(grpc::ServerContext* context) {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  streams_.erase(context);
}

void CallGuard::cancelStreams() {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  streams_cancelled_ = true;
  for (grpc::ServerContext* context : streams_) context->TryCancel();
}

}  // namespace cenote::server
