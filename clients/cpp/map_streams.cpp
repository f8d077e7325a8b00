// map_streams.cpp: MapClient's streaming calls: the ingest streams (points, stereo frames, poses)
// and the update stream (Subscription on a thread of its own, watch() on the caller's).
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

#include "clients/cpp/detail/client_impl.h"
#include "clients/cpp/detail/wire.h"
#include "clients/cpp/map_client.h"

namespace cenote::client {

using detail::throwIfFailed;

// ---- Ingest streams ----

// What each ingest stream sends and receives on the wire.
template <typename Item>
struct StreamWire;
template <>
struct StreamWire<PointBatch> {
  using Request = v1::PointBatch;
  using Reply = v1::BatchAck;
  static constexpr auto kOpen = &v1::Ingest::Stub::StreamPoints;
};
template <>
struct StreamWire<StereoFrame> {
  using Request = v1::StereoFrame;
  using Reply = v1::FrameAck;
  static constexpr auto kOpen = &v1::Ingest::Stub::StreamFrames;
};
template <>
struct StreamWire<PoseStamped> {
  using Request = v1::PoseStamped;
  using Reply = v1::PoseAck;
  static constexpr auto kOpen = &v1::Ingest::Stub::StreamPoses;
};

template <typename Item, typename Ack>
struct IngestStream<Item, Ack>::Impl {
  using Request = typename StreamWire<Item>::Request;
  using Reply = typename StreamWire<Item>::Reply;
  std::shared_ptr<v1::Ingest::Stub> stub;
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientReaderWriter<Request, Reply>> stream;
  std::mutex write_mutex;  // writes_done and write may come from different threads
  bool writes_done = false;
  bool finished = false;
};

template <typename Item, typename Ack>
IngestStream<Item, Ack>::IngestStream(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

template <typename Item, typename Ack>
std::unique_ptr<IngestStream<Item, Ack>> IngestStream<Item, Ack>::open(MapClient::Impl& client) {
  auto impl = std::make_unique<Impl>();
  impl->stub = client.ingest;
  client.prepare(impl->context, 0.0);
  impl->stream = (impl->stub.get()->*StreamWire<Item>::kOpen)(&impl->context);
  return std::unique_ptr<IngestStream>(new IngestStream(std::move(impl)));
}

template <typename Item, typename Ack>
IngestStream<Item, Ack>::~IngestStream() {
  if (!impl_->finished) {
    impl_->context.TryCancel();
    impl_->stream->Finish();
  }
}

template <typename Item, typename Ack>
bool IngestStream<Item, Ack>::write(const Item& item) {
  typename Impl::Request message;
  detail::toWire(item, &message);
  std::lock_guard lock(impl_->write_mutex);
  return !impl_->writes_done && impl_->stream->Write(message);
}

template <typename Item, typename Ack>
bool IngestStream<Item, Ack>::read(Ack& ack) {
  typename Impl::Reply message;
  if (!impl_->stream->Read(&message)) return false;
  ack = detail::fromWire(message);
  return true;
}

template <typename Item, typename Ack>
void IngestStream<Item, Ack>::finish(std::vector<Ack>* remaining) {
  {
    std::lock_guard lock(impl_->write_mutex);
    if (!impl_->writes_done) impl_->stream->WritesDone();
    impl_->writes_done = true;
  }
  Ack ack;
  while (read(ack)) {
    if (remaining) remaining->push_back(ack);
  }
  impl_->finished = true;
  throwIfFailed(impl_->stream->Finish());
}

template class IngestStream<PointBatch, BatchAck>;
template class IngestStream<StereoFrame, FrameAck>;
template class IngestStream<PoseStamped, PoseAck>;

std::unique_ptr<PointsStream> MapClient::openPointsStream() { return PointsStream::open(*impl_); }

std::unique_ptr<FramesStream> MapClient::openFramesStream() { return FramesStream::open(*impl_); }

std::unique_ptr<PosesStream> MapClient::openPosesStream() { return PosesStream::open(*impl_); }

std::vector<BatchAck> MapClient::streamPoints(const std::vector<PointBatch>& batches) {
  std::unique_ptr<PointsStream> stream = openPointsStream();
  std::thread writer([&] {
    for (const PointBatch& batch : batches) {
      if (!stream->write(batch)) break;
    }
  });
  std::vector<BatchAck> acks;
  BatchAck ack;
  while (acks.size() < batches.size() && stream->read(ack)) acks.push_back(ack);
  writer.join();
  stream->finish(&acks);
  return acks;
}

// ---- Updates ----

struct Subscription::Impl {
  std::shared_ptr<v1::Updates::Stub> stub;
  grpc::ClientContext context;
  std::thread thread;
  std::atomic<bool> active{true};
  std::atomic<bool> cancelled{false};
  std::atomic<uint64_t> received{0};
  grpc::Status status;
  std::exception_ptr callback_error;  // what on_update threw (the stream was then cancelled)
};

namespace {
v1::SubscribeRequest subscribeRequest(const SubscribeOptions& options) {
  v1::SubscribeRequest request;
  if (!options.region.isEmpty()) detail::toWire(options.region, request.mutable_region());
  request.set_include_probabilities(options.include_probabilities);
  return request;
}
}  // namespace

std::unique_ptr<Subscription> MapClient::subscribe(const SubscribeOptions& options,
                                                   std::function<void(const MapUpdate&)> on_update) {
  auto impl = std::make_unique<Subscription::Impl>();
  impl->stub = impl_->updates;
  impl_->prepare(impl->context, 0.0);
  Subscription::Impl* raw = impl.get();
  raw->thread = std::thread([raw, request = subscribeRequest(options), on_update = std::move(on_update)] {
    std::unique_ptr<grpc::ClientReader<v1::MapUpdate>> reader = raw->stub->Subscribe(&raw->context, request);
    v1::MapUpdate message;
    MapUpdate update;
    while (reader->Read(&message)) {
      if (raw->cancelled) continue;  // drain: the call ends once the cancellation lands
      detail::fromWire(message, update);
      raw->received.fetch_add(1);
      try {
        on_update(update);
      } catch (...) {
        // An exception must not leave this thread (std::terminate): keep it for wait().
        raw->callback_error = std::current_exception();
        raw->cancelled = true;
        raw->context.TryCancel();
      }
    }
    raw->status = reader->Finish();
    raw->active = false;
  });
  return std::unique_ptr<Subscription>(new Subscription(std::move(impl)));
}

Subscription::Subscription(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Subscription::~Subscription() { cancel(); }

void Subscription::cancel() {
  impl_->cancelled = true;
  impl_->context.TryCancel();
  if (impl_->thread.joinable()) impl_->thread.join();
}

bool Subscription::isActive() const { return impl_->active; }
uint64_t Subscription::updatesReceived() const { return impl_->received; }

void Subscription::wait() {
  if (impl_->thread.joinable()) impl_->thread.join();
  if (impl_->callback_error) std::rethrow_exception(impl_->callback_error);
  if (!impl_->cancelled) throwIfFailed(impl_->status);
}

void MapClient::watch(const SubscribeOptions& options, const std::function<bool(const MapUpdate&)>& on_update) {
  grpc::ClientContext context;
  impl_->prepare(context, 0.0);
  std::unique_ptr<grpc::ClientReader<v1::MapUpdate>> reader = impl_->updates->Subscribe(&context,
                                                                                        subscribeRequest(options));
  v1::MapUpdate message;
  MapUpdate update;
  bool stopped = false;
  while (reader->Read(&message)) {
    detail::fromWire(message, update);
    if (!on_update(update)) {
      stopped = true;
      context.TryCancel();
      break;
    }
  }
  const grpc::Status status = reader->Finish();
  if (!stopped) throwIfFailed(status);
}

}  // namespace cenote::client
