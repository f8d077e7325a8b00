#include "server/call_guard.h"

#include <algorithm>
#include <fstream>

namespace cenote::server {
namespace {

// Compares in time independent of where the strings first differ.
bool equalConstantTime(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i % std::max<size_t>(b.size(), 1)]);
  return diff == 0 && !b.empty();
}

}  // namespace

std::string Authenticator::readTokenFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("token file " + path + " cannot be read");
  std::string line;
  std::getline(in, line);
  const size_t first = line.find_first_not_of(" \t\r\n");
  const size_t last = line.find_last_not_of(" \t\r\n");
  if (first == std::string::npos) throw Error("token file " + path + " holds no token on its first line");
  return line.substr(first, last - first + 1);
}

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
  if (samples_.size() < kSamples) {
    samples_.push_back(static_cast<float>(ms));
  } else {
    samples_[calls_ % kSamples] = static_cast<float>(ms);
  }
  ++calls_;
  if (!ok) ++errors_;
}

MethodSummary MethodStats::summary(const std::string& method) const {
  std::vector<float> sorted;
  MethodSummary s;
  s.method = method;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    sorted = samples_;
    s.calls = calls_;
    s.errors = errors_;
  }
  if (sorted.empty()) return s;
  std::sort(sorted.begin(), sorted.end());
  s.p50_ms = sorted[sorted.size() / 2];
  s.p99_ms = sorted[std::min(sorted.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(sorted.size())))];
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
