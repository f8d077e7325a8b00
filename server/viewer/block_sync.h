// block_sync.h: what one viewer client has of the map, and the next SceneUpdate to bring it closer
// within a byte budget, with level of detail.
// The client has each block at a level: none, coarse (the block as one cube) or full (a cube per
// occupied voxel). Blocks the map changed are dirty. next() sends the dirty blocks nearest the
// camera first: when the budget does not cover them all at full detail, every dirty block it
// reaches is first given a coarse cube, then the nearest are upgraded to full while the budget
// lasts; blocks the budget does not reach stay dirty. With budget to spare, coarse blocks are
// refined, nearest first. So a slow link gets the whole map's shape first and detail later, and
// what waits is a set of blocks, never a queue of messages: a block changed ten times is sent once,
// as it is then.
// Most changes of a block only carve free space or move a probability: a changed block whose
// occupied voxels are those the client has at full detail is not sent again then (it would cost as
// much as a new one). It is only stale: its colours and probabilities are refreshed with budget to
// spare, once refresh_s has passed since it was sent.
// Blocks are read from the map when sent (ConstAccessor), so the client converges to the map.
// Units: metres, world frame. Threads: one thread per BlockSync.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "mapping/occupancy_map.h"
#include "server/viewer/scene_messages.h"

namespace cenote::server::viewer {

struct SyncStep {
  std::string message;  // a SceneUpdate; empty when there was nothing to send
  size_t full_blocks = 0, coarse_blocks = 0, deleted_blocks = 0;
  uint64_t full_voxels = 0;
};

class BlockSync {
 public:
  // resend_s: a block the client has is sent again at most this often (it waits, dirty, while the
  // map goes on changing it); refresh_s: the same for a stale block (see above).
  BlockSync(std::string frame_id, ColorBy color_by, double refresh_s = 5.0, double resend_s = 0.0)
      : frame_id_(std::move(frame_id)),
        color_by_(color_by),
        refresh_ns_(static_cast<uint64_t>(refresh_s * 1e9)),
        resend_ns_(static_cast<uint64_t>(resend_s * 1e9)) {}

  // Every block the client has and every block given (the map's known blocks) become dirty: the
  // whole map is sent again (a new client, or a change feed that dropped changes).
  void markAll(const std::vector<mapping::BlockIndex>& known_blocks);
  void markChanged(const std::vector<mapping::BlockIndex>& blocks);

  // The next update, at most about budget_bytes long (a single block bigger than that is sent
  // coarse, which always fits once: the budget's floor is one coarse block).
  SyncStep next(const mapping::OccupancyMap::ConstAccessor& access, const Eigen::Vector3d& camera_m, double budget_bytes,
                uint64_t time_ns);

  // Nothing dirty and nothing coarse: the client has every occupied voxel of the map (stale
  // blocks may still have older colours and probabilities).
  bool settled() const { return dirty_.empty() && coarse_ == 0; }
  size_t dirtyBlocks() const { return dirty_.size(); }
  size_t coarseBlocks() const { return coarse_; }
  size_t staleBlocks() const { return stale_.size(); }

 private:
  enum class Lod : uint8_t { kCoarse = 1, kFull = 2 };
  struct Sent {
    Lod lod = Lod::kCoarse;
    std::array<uint64_t, 8> occupied{};  // the block's occupied voxels when sent
    uint64_t time_ns = 0;
  };
  static uint64_t key(const mapping::BlockIndex& b);
  static mapping::BlockIndex unkey(uint64_t k);
  void setLevel(uint64_t k, Lod lod, const std::array<uint64_t, 8>& occupied, uint64_t time_ns);
  void forget(uint64_t k);

  std::string frame_id_;
  ColorBy color_by_;
  uint64_t refresh_ns_;
  uint64_t resend_ns_;
  std::unordered_map<uint64_t, Sent> sent_;  // blocks the client has, and as what
  std::unordered_set<uint64_t> dirty_;
  std::unordered_set<uint64_t> stale_;  // full blocks changed since sent, with the same occupied voxels
  size_t coarse_ = 0;                   // blocks of sent_ at kCoarse
};

}  // namespace cenote::server::viewer
