// map_mirror.cpp: MapMirror.
#include "clients/cpp/map_mirror.h"

#include <cmath>

namespace cenote::client {

void MapMirror::apply(const MapUpdate& update) {
  std::lock_guard lock(mutex_);
  if (update.snapshot && !in_snapshot_) {
    // The first message of a (re)snapshot: what follows is the whole map.
    blocks_.clear();
    in_snapshot_ = true;
    synced_ = false;
  }
  if (update.voxel_size_m > 0.0) voxel_size_m_ = update.voxel_size_m;
  for (const UpdateBlock& block : update.blocks) {
    bool any_known = false;
    for (VoxelState s : block.states) any_known |= s != VoxelState::kUnknown;
    if (any_known) {
      blocks_[block.index] = block.states;
    } else {
      blocks_.erase(block.index);
    }
  }
  if (update.snapshot && update.snapshot_complete) {
    in_snapshot_ = false;
    synced_ = true;
  }
  sequence_ = update.sequence;
}

bool MapMirror::isSynced() const {
  std::lock_guard lock(mutex_);
  return synced_;
}

uint64_t MapMirror::sequence() const {
  std::lock_guard lock(mutex_);
  return sequence_;
}

double MapMirror::voxelSize() const {
  std::lock_guard lock(mutex_);
  return voxel_size_m_;
}

VoxelState MapMirror::state(const Eigen::Vector3i& ijk) const {
  const Eigen::Vector3i block(ijk.x() >> 3, ijk.y() >> 3, ijk.z() >> 3);
  const int offset = ((ijk.x() & 7) << 6) | ((ijk.y() & 7) << 3) | (ijk.z() & 7);
  std::lock_guard lock(mutex_);
  const auto it = blocks_.find(block);
  return it == blocks_.end() ? VoxelState::kUnknown : it->second[static_cast<size_t>(offset)];
}

VoxelState MapMirror::stateAt(const Eigen::Vector3d& point_m) const {
  const double s = voxelSize();
  if (s <= 0.0 || !point_m.allFinite()) return VoxelState::kUnknown;
  const Eigen::Vector3i ijk(static_cast<int>(std::floor(point_m.x() / s)), static_cast<int>(std::floor(point_m.y() / s)),
                            static_cast<int>(std::floor(point_m.z() / s)));
  return state(ijk);
}

uint64_t MapMirror::count(VoxelState state) const {
  std::lock_guard lock(mutex_);
  uint64_t n = 0;
  for (const auto& [index, states] : blocks_) {
    for (VoxelState s : states) n += s == state;
  }
  return n;
}

uint64_t MapMirror::occupied() const { return count(VoxelState::kOccupied); }

uint64_t MapMirror::free() const { return count(VoxelState::kFree); }

size_t MapMirror::numBlocks() const {
  std::lock_guard lock(mutex_);
  return blocks_.size();
}

std::vector<std::pair<Eigen::Vector3i, VoxelState>> MapMirror::knownVoxels() const {
  std::lock_guard lock(mutex_);
  std::vector<std::pair<Eigen::Vector3i, VoxelState>> out;
  for (const auto& [block, states] : blocks_) {
    for (int offset = 0; offset < 512; ++offset) {
      const VoxelState s = states[static_cast<size_t>(offset)];
      if (s == VoxelState::kUnknown) continue;
      out.emplace_back(
          Eigen::Vector3i(block.x() * 8 + (offset >> 6), block.y() * 8 + ((offset >> 3) & 7), block.z() * 8 + (offset & 7)),
          s);
    }
  }
  return out;
}

}  // namespace cenote::client
