#include "server/access/call_guard.h"

namespace cenote::server {
namespace {

// Compares in a time that does not depend on where the strings first differ (the token's length
// is not the secret).
bool equalConstantTime(const std::string& given, const std::string& token) {
  if (given.size() != token.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < given.size(); ++i) diff |= static_cast<unsigned char>(given[i] ^ token[i]);
  return diff == 0;
}

}  // namespace

grpc::Status Authenticator::check(const grpc::ServerContext& context) const {
  if (token_.empty()) return grpc::Status::OK;
  const auto& metadata = context.client_metadata();
  const auto it = metadata.find("authorization");
  if (it == metadata.end()) {
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "missing token: send metadata 'authorization: Bearer <token>'");
  }
  const std::string value(it->second.data(), it->second.size());
  static const std::string kPrefix = "Bearer ";
  if (value.rfind(kPrefix, 0) != 0 || !equalConstantTime(value.substr(kPrefix.size()), token_)) {
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "wrong token");
  }
  return grpc::Status::OK;
}

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

}  // namespace cenote::server
