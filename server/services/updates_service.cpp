#include "server/services/updates_service.h"

#include <optional>

#include "mapping/map_range.h"
#include "server/wire/wire.h"

namespace cenote::server {
namespace {

constexpr size_t kBlocksPerMessage = 256;  // about 130 KiB of states per message

// What one subscriber asked for.
struct BlockFilter {
  // Blocks holding a voxel of it: those whose centre lies in the requested box, clipped to the map's
  // range (mapping/map_range.h). All when absent (no box, or an empty one); none when the box holds
  // no voxel centre.
  std::optional<mapping::VoxelBox> region;
  bool probabilities = false;

  bool accepts(const mapping::BlockIndex& b) const {
    if (!region) return true;
    if (region->isEmpty()) return false;
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

// Sends `blocks` in messages of kBlocksPerMessage. @return false when the client has gone.
bool sendBlocks(grpc::ServerWriter<v1::MapUpdate>* writer, const mapping::OccupancyMap& map,
                const std::vector<mapping::BlockIndex>& blocks, const BlockFilter& filter, v1::MapUpdate header,
                bool snapshot) {
  std::vector<mapping::BlockIndex> wanted;
  for (const auto& b : blocks)
    if (filter.accepts(b)) wanted.push_back(b);
  if (wanted.empty() && !snapshot) return true;
  size_t next = 0;
  do {
    v1::MapUpdate update = header;
    update.set_voxel_size_m(map.voxelSize());
    {
      // One accessor per message: writers wait for at most one message's worth of reading.
      const mapping::OccupancyMap::ConstAccessor access = map.constAccessor();
      for (size_t end = std::min(wanted.size(), next + kBlocksPerMessage); next < end; ++next) {
        fillBlock(access, wanted[next], filter, update.add_blocks());
      }
    }
    if (snapshot) update.set_snapshot_complete(next == wanted.size());
    if (!writer->Write(update)) return false;
  } while (next < wanted.size());
  return true;
}

bool sendSnapshot(grpc::ServerWriter<v1::MapUpdate>* writer, const mapping::OccupancyMap& map, const BlockFilter& filter,
                  bool resync) {
  v1::MapUpdate header;
  header.set_sequence(map.version());
  header.set_snapshot(true);
  header.set_resync(resync);
  std::vector<mapping::BlockIndex> blocks;
  {
    const mapping::OccupancyMap::ConstAccessor access = map.constAccessor();
    blocks = access.knownBlocks();
  }
  return sendBlocks(writer, map, blocks, filter, header, true);
}

}  // namespace

grpc::Status UpdatesService::Subscribe(grpc::ServerContext* context, const v1::SubscribeRequest* request,
                                       grpc::ServerWriter<v1::MapUpdate>* writer) {
  return guard_.run(context, "Updates/Subscribe", [&] {
    const mapping::OccupancyMap& map = host_.map();
    BlockFilter filter;
    filter.probabilities = request->include_probabilities();
    if (request->has_region()) {
      const mapping::Aabb box = finiteBox(request->region(), "region");
      if (!box.isEmpty()) filter.region = mapping::voxelsOfBox(box, map.voxelSize(), "region").voxels;
    }
    // Subscribe before reading the snapshot: a change made meanwhile is sent twice, never missed.
    const std::shared_ptr<Subscription> subscription = host_.feed().subscribe();
    struct Unsubscribe {
      ChangeFeed& feed;
      const std::shared_ptr<Subscription>& s;
      ~Unsubscribe() { feed.unsubscribe(s); }
    } unsubscribe{host_.feed(), subscription};

    if (!sendSnapshot(writer, map, filter, false)) return grpc::Status::OK;
    MapChange change;
    while (!context->IsCancelled()) {
      switch (subscription->next(change, std::chrono::milliseconds(200))) {
        case Subscription::Next::kClosed: return grpc::Status::OK;
        case Subscription::Next::kTimeout: break;
        case Subscription::Next::kResync:
          if (!sendSnapshot(writer, map, filter, true)) return grpc::Status::OK;
          break;
        case Subscription::Next::kChange: {
          v1::MapUpdate header;
          header.set_sequence(change.version);
          toWire(change.delta.changed_m, header.mutable_changed_bounds());
          if (!sendBlocks(writer, map, change.delta.changed_blocks, filter, header, false)) return grpc::Status::OK;
          break;
        }
      }
    }
    return grpc::Status::OK;
  });
}

}  // namespace cenote::server
