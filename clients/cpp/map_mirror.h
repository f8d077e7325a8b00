// map_mirror.h: a local copy of the server's voxel states kept from its update stream
// (MapClient::subscribe), so that a planner or viewer reads the map without a round trip.
// Follows updates.proto: snapshot messages first (the last with snapshot_complete), then changes;
// a resync snapshot replaces everything; an all-unknown block is a cleared one and is dropped.
// Units: metres, world frame; voxel indices as mapping/voxel_types.h.
// Threads: apply() and the readers may run on different threads (an internal mutex).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "clients/cpp/client_types.h"

namespace cenote::client {

class MapMirror {
 public:
  void apply(const MapUpdate& update);

  // True once the first full snapshot has arrived (and again after a resync completes).
  bool isSynced() const;
  // The sequence (map version) of the last update applied.
  uint64_t sequence() const;
  double voxelSize() const;

  VoxelState state(const Eigen::Vector3i& ijk) const;
  // State of the voxel holding a point; unknown before the first update (voxel size unknown).
  VoxelState stateAt(const Eigen::Vector3d& point_m) const;
  // Number of occupied / free voxels held.
  uint64_t occupied() const;
  uint64_t free() const;
  size_t numBlocks() const;
  // Every known voxel with its state, in no particular order.
  std::vector<std::pair<Eigen::Vector3i, VoxelState>> knownVoxels() const;

 private:
  struct BlockKeyHash {
    size_t operator()(const Eigen::Vector3i& b) const {
      return (static_cast<size_t>(static_cast<uint32_t>(b.x())) * 73856093u) ^
             (static_cast<size_t>(static_cast<uint32_t>(b.y())) * 19349663u) ^
             (static_cast<size_t>(static_cast<uint32_t>(b.z())) * 83492791u);
    }
  };
  struct BlockKeyEqual {
    bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
  };
  using BlockStates = std::array<VoxelState, 512>;

  uint64_t count(VoxelState state) const;  // voxels in `state` over all blocks

  mutable std::mutex mutex_;
  std::unordered_map<Eigen::Vector3i, BlockStates, BlockKeyHash, BlockKeyEqual> blocks_;
  bool synced_ = false;
  bool in_snapshot_ = false;
  uint64_t sequence_ = 0;
  double voxel_size_m_ = 0.0;
};

}  // namespace cenote::client
