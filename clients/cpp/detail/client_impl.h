// client_impl.h: what MapClient holds behind its pimpl (the channel, the four service stubs, the
// options) and how every call is prepared. Private to the client library (map_client.cpp,
// map_streams.cpp).
// Threads: stubs are thread safe; Impl is read-only after construction.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>

#include "cenote/v1/admin.grpc.pb.h"
#include "cenote/v1/ingest.grpc.pb.h"
#include "cenote/v1/query.grpc.pb.h"
#include "cenote/v1/updates.grpc.pb.h"
#include "clients/cpp/batching.h"
#include "clients/cpp/map_client.h"

namespace cenote::client {

namespace detail {
inline void throwIfFailed(const grpc::Status& status) {
  if (!status.ok()) throw RpcError(status.error_code(), status.error_message());
}
}  // namespace detail

struct MapClient::Impl {
  ClientOptions options;
  std::shared_ptr<grpc::Channel> channel;
  std::shared_ptr<v1::Query::Stub> query;
  std::shared_ptr<v1::Ingest::Stub> ingest;
  std::shared_ptr<v1::Updates::Stub> updates;
  std::shared_ptr<v1::Admin::Stub> admin;

  Impl(std::shared_ptr<grpc::Channel> ch, const ClientOptions& opts)
      : options(opts),
        channel(std::move(ch)),
        query(v1::Query::NewStub(channel)),
        ingest(v1::Ingest::NewStub(channel)),
        updates(v1::Updates::NewStub(channel)),
        admin(v1::Admin::NewStub(channel)) {}

  // Authorization and (for unary calls) the deadline.
  void prepare(grpc::ClientContext& context, double deadline_s) const {
    if (!options.token.empty()) context.AddMetadata("authorization", "Bearer " + options.token);
    if (deadline_s > 0.0) {
      context.set_deadline(std::chrono::system_clock::now() +
                           std::chrono::microseconds(static_cast<int64_t>(deadline_s * 1e6)));
    }
  }

  template <typename Stub, typename Request, typename Reply>
  void unary(Stub& stub, grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Reply*), const Request& request,
             Reply& reply) const {
    grpc::ClientContext context;
    prepare(context, options.deadline_s);
    detail::throwIfFailed((stub.*method)(&context, request, &reply));
  }

  // A query over `count` items, one call per batch of at most options.max_batch_items, in order:
  // for each [begin, end), `fill(begin, end)` writes the batch into `request` (replacing the last
  // one's items; fields common to all batches are set once by the caller), the call answers into
  // `reply`, and `take(begin, end)` appends what it says.
  template <typename Request, typename Reply, typename Fill, typename Take>
  void batched(size_t count, grpc::Status (v1::Query::Stub::*method)(grpc::ClientContext*, const Request&, Reply*),
               Request& request, Reply& reply, Fill fill, Take take) const {
    for (const auto& [begin, end] : batchRanges(count, options.max_batch_items)) {
      fill(begin, end);
      unary(*query, method, request, reply);
      take(begin, end);
    }
  }
};

}  // namespace cenote::client
