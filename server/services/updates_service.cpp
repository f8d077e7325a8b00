#include "server/services/updates_service.h"

#include <optional>

#include "mapping/map_range.h"
#include "server/wire/wire.h"

namespace cenote::server {
namespace {

constexpr size_t kBlocksPerMessage = 256;  // about 130 KiB of states per message

// What one subscriber asked for.
struct BlockFilter {
  std::optional<mapping::VoxelBox> region;  // blocks touching it; all when absent
  bool probabilities = false;

  bool accepts(const mapping::BlockIndex& b) const {
    if (!region) return true;
    const mapping::VoxelIndex lo = b * mapping::kBlockSide, hi = lo.array() + (mapping::kBlockSide - 1);
    return (hi.array() >= region->min.array()).all() && (lo.array() <= region->max.array()).all();
  }
};

void fillBlock(const mapping::OccupancyMap::ConstAccessor& access, const mapping::BlockIndex& index,
               const BlockFilter& filter, v1::Block* out) {
  mapping::BlockView view;
  access.readBlock(index, view);  // false: all unknown (a cleared block)
  const mapping::LogOddsModel& model = access.map().model();
  toWire(index, out->mutable_index());
  std::string states(mapping::kBlockVoxels, static_cast<char>(v1::VOXEL_STATE_UNKNOWN));
  if (filter.probabilities) out->mutable_probabilities()->Reserve(mapping::kBlockVoxels);
  for (int i = 0; i < mapping::kBlockVoxels; ++i) {
    const bool known = (view.known[i >> 6] >> (i & 63)) & 1u;
    if (known) {
      states[i] = static_cast<char>(model.isOccupied(view.log_odds[i]) ? v1::VOXEL_STATE_OCCUPIED : v1::VOXEL_STATE_FREE);
    }
    if (filter.probabilities) {
      out->add_probabilities(known ? static_cast<float>(mapping::probability(view.log_odds[i])) : 0.5f);
    }
  }
  out->set_states(std::move(states));
}

// A call refused before it subscribed (bad region, too many subscribers, deadline passed).
class Refused final : public grpc::ServerWriteReactor<v1::MapUpdate> {
 public:
  explicit Refused(grpc::Status status) { Finish(std::move(status)); }
  void OnDone() override { delete this; }
};

}  // namespace

namespace detail {

// One Subscribe call. It owns itself (self_) from start() until gRPC's OnDone; the sender's queue
// and the feed's notify hold it (or a weak reference) meanwhile. Every state change is under
// mutex_: pump() on the sender thread, OnWriteDone / OnCancel on gRPC's threads.
class Subscriber final : public grpc::ServerWriteReactor<v1::MapUpdate>, public std::enable_shared_from_this<Subscriber> {
 public:
  Subscriber(UpdatesService& service, BlockFilter filter) : service_(service), filter_(std::move(filter)) {}

  // Subscribes to the feed before anything is read of the map: a change made while the snapshot
  // is read is sent twice, never missed.
  void start() {
    self_ = shared_from_this();
    subscription_ = service_.host_.feed().subscribe();
    subscription_->setNotify([weak = std::weak_ptr<Subscriber>(self_), &service = service_] {
      if (std::shared_ptr<Subscriber> s = weak.lock()) service.post(std::move(s));
    });
    service_.post(self_);
  }

  // Builds and starts the next message, if there is one and none is in flight.
  void pump() {
    queued_ = false;
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_ || writing_) return;
    if (subscription_->closed()) return finishLocked(shuttingDown());
    const mapping::OccupancyMap& map = service_.host_.map();
    while (!pending_) {
      if (snapshot_due_) {
        startSnapshot(map, false);
        snapshot_due_ = false;
        break;
      }
      MapChange change;
      switch (subscription_->next(change, std::chrono::milliseconds(0))) {
        case Subscription::Next::kClosed: return finishLocked(shuttingDown());
        case Subscription::Next::kTimeout: return;  // the feed's notify posts it again
        case Subscription::Next::kResync: startSnapshot(map, true); break;
        case Subscription::Next::kChange: {
          header_.Clear();
          header_.set_sequence(change.version);
          toWire(change.delta.changed_m, header_.mutable_changed_bounds());
          blocks_.clear();
          for (const auto& b : change.delta.changed_blocks)
            if (filter_.accepts(b)) blocks_.push_back(b);
          next_ = 0;
          pending_ = !blocks_.empty();
          snapshot_ = false;
          break;
        }
      }
    }
    message_ = header_;
    message_.set_voxel_size_m(map.voxelSize());
    {
      // One accessor per message: writers wait for at most one message's worth of reading.
      const mapping::OccupancyMap::ConstAccessor access = map.constAccessor();
      for (size_t end = std::min(blocks_.size(), next_ + kBlocksPerMessage); next_ < end; ++next_) {
        fillBlock(access, blocks_[next_], filter_, message_.add_blocks());
      }
    }
    if (snapshot_) message_.set_snapshot_complete(next_ == blocks_.size());
    pending_ = next_ < blocks_.size();
    writing_ = true;
    StartWrite(&message_);
  }

  // True when it was not already on the sender's queue (then the caller queues it).
  bool markQueued() { return !queued_.exchange(true); }

  void OnWriteDone(bool ok) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      writing_ = false;
      if (!ok) {
        if (!finished_) finishLocked(grpc::Status(grpc::StatusCode::CANCELLED, "the subscriber went away"));
        return;
      }
    }
    service_.post(shared_from_this());
  }

  void OnCancel() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!finished_) finishLocked(grpc::Status::CANCELLED);
  }

  void OnDone() override {
    service_.host_.feed().unsubscribe(subscription_);
    --service_.subscribers_;
    self_.reset();  // may delete this: the last statement
  }

 private:
  void startSnapshot(const mapping::OccupancyMap& map, bool resync) {
    header_.Clear();
    header_.set_sequence(map.version());
    header_.set_snapshot(true);
    header_.set_resync(resync);
    std::vector<mapping::BlockIndex> known;
    {
      const mapping::OccupancyMap::ConstAccessor access = map.constAccessor();
      known = access.knownBlocks();
    }
    blocks_.clear();
    for (const auto& b : known)
      if (filter_.accepts(b)) blocks_.push_back(b);
    next_ = 0;
    pending_ = true;  // at least one message, the one with snapshot_complete
    snapshot_ = true;
  }

  static grpc::Status shuttingDown() {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                        "cenote-server is shutting down: subscribe again once it is back (a snapshot first, as always)");
  }

  void finishLocked(grpc::Status status) {
    finished_ = true;
    Finish(std::move(status));
  }

  UpdatesService& service_;
  const BlockFilter filter_;
  std::shared_ptr<Subscription> subscription_;
  std::shared_ptr<Subscriber> self_;
  std::atomic<bool> queued_{false};
  std::mutex mutex_;
  bool writing_ = false, finished_ = false;
  bool snapshot_due_ = true;  // the first snapshot, not yet begun
  // The snapshot or change being sent: its header, its blocks, the next block to send.
  bool pending_ = false, snapshot_ = false;
  v1::MapUpdate header_;
  std::vector<mapping::BlockIndex> blocks_;
  size_t next_ = 0;
  v1::MapUpdate message_;  // the one in flight
};

}  // namespace detail

UpdatesService::UpdatesService(MapHost& host, CallGuard& guard, int max_subscribers)
    : host_(host), guard_(guard), max_subscribers_(max_subscribers), sender_([this] { sendLoop(); }) {}

UpdatesService::~UpdatesService() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  ready_.notify_all();
  sender_.join();
}

void UpdatesService::post(std::shared_ptr<detail::Subscriber> s) {
  if (!s->markQueued()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(s));
  }
  ready_.notify_one();
}

void UpdatesService::sendLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    ready_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) return;
    std::shared_ptr<detail::Subscriber> s = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    s->pump();
    s.reset();  // the last reference may go here, outside the queue's lock
    lock.lock();
  }
}

grpc::ServerWriteReactor<v1::MapUpdate>* UpdatesService::Subscribe(grpc::CallbackServerContext* context,
                                                                   const v1::SubscribeRequest* request) {
  std::shared_ptr<detail::Subscriber> subscriber;
  const grpc::Status status = guard_.run(context, "Updates/Subscribe", [&] {
    BlockFilter filter;
    filter.probabilities = request->include_probabilities();
    if (request->has_region()) {
      const mapping::Aabb box = finiteBox(request->region(), "region");
      const mapping::OccupancyMap& map = host_.map();
      if (!box.isEmpty()) filter.region = mapping::voxelsOfBox(box, map.voxelSize(), "region").voxels;
    }
    if (++subscribers_ > max_subscribers_) {
      --subscribers_;
      throw resourceExhausted("already " + std::to_string(max_subscribers_) +
                              " update subscribers: the limit server.limits.max_subscribers");
    }
    subscriber = std::make_shared<detail::Subscriber>(*this, std::move(filter));
    return grpc::Status::OK;
  });
  if (!status.ok()) return new Refused(status);
  subscriber->start();
  return subscriber.get();
}

}  // namespace cenote::server
