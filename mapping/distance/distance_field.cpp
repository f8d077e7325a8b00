#include "mapping/distance/distance_field.h"

#include <cmath>
#include <limits>
#include <mutex>
#include <queue>
#include <unordered_map>

#include "mapping/detail/block_table.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

constexpr int kNone = std::numeric_limits<int>::min();
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Cell {
  VoxelIndex obstacle = VoxelIndex::Constant(kNone);  // nearest obstacle voxel, or none
  float dist2 = kInf;                                  // squared distance to it, in voxels^2
  bool is_obstacle = false;                            // occupied in the map as last seen
  bool raise = false;                                  // queued to clear
  bool hasObstacle() const { return obstacle.x() != kNone; }
  void clear() {
    obstacle = VoxelIndex::Constant(kNone);
    dist2 = kInf;
  }
};

struct Block {
  std::array<Cell, kBlockVoxels> cells;
};

struct QueueEntry {
  float dist2;
  VoxelIndex ijk;
  bool operator>(const QueueEntry& o) const { return dist2 > o.dist2; }
};

}  // namespace

struct DistanceField::Impl {
  std::unordered_map<uint64_t, std::unique_ptr<Block>> blocks;
  std::priority_queue<QueueEntry, std::vector<QueueEntry>, std::greater<QueueEntry>> open;
  float max_dist2 = 0.0f;

  Cell* find(const VoxelIndex& ijk) const {
    const auto it = blocks.find(detail::packIndex(blockOf(ijk)));
    return it == blocks.end() ? nullptr : &it->second->cells[offsetInBlock(ijk)];
  }
  Cell& get(const VoxelIndex& ijk) {
    auto& block = blocks[detail::packIndex(blockOf(ijk))];
    if (!block) block = std::make_unique<Block>();
    return block->cells[offsetInBlock(ijk)];
  }
  bool stillObstacle(const VoxelIndex& ijk) const {
    const Cell* c = find(ijk);
    return c != nullptr && c->is_obstacle;
  }

  void setObstacle(const VoxelIndex& ijk) {
    Cell& c = get(ijk);
    c.is_obstacle = true;
    c.obstacle = ijk;
    c.dist2 = 0.0f;
    c.raise = false;
    open.push({0.0f, ijk});
  }
  void removeObstacle(const VoxelIndex& ijk) {
    Cell& c = get(ijk);
    c.is_obstacle = false;
    c.clear();
    c.raise = true;
    open.push({0.0f, ijk});
  }

  void propagate() {
    while (!open.empty()) {
      const QueueEntry e = open.top();
      open.pop();
      Cell* c = find(e.ijk);
      if (c == nullptr) continue;
      if (c->raise) {
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              if (dx == 0 && dy == 0 && dz == 0) continue;
              const VoxelIndex n = e.ijk + VoxelIndex(dx, dy, dz);
              Cell* nc = find(n);
              if (nc == nullptr || !nc->hasObstacle() || nc->raise) continue;
              if (!stillObstacle(nc->obstacle)) {
                const float old = nc->dist2;
                nc->clear();
                nc->raise = true;
                open.push({old, n});
              } else {
                open.push({nc->dist2, n});
              }
            }
        c->raise = false;
        // A cleared cell may sit next to valid ones: they re-lower it when popped.
        continue;
      }
      if (!c->hasObstacle() || e.dist2 > c->dist2) continue;  // stale entry
      if (!stillObstacle(c->obstacle)) continue;
      const VoxelIndex obstacle = c->obstacle;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            if (dx == 0 && dy == 0 && dz == 0) continue;
            const VoxelIndex n = e.ijk + VoxelIndex(dx, dy, dz);
            const float d2 = static_cast<float>((n - obstacle).squaredNorm());
            if (d2 > max_dist2) continue;
            Cell& nc = get(n);
            if (nc.raise || d2 >= nc.dist2) continue;
            nc.dist2 = d2;
            nc.obstacle = obstacle;
            open.push({d2, n});
          }
    }
  }
};

DistanceField::DistanceField(const OccupancyMap& map)
    : map_(map), max_distance_m_(map.config().max_distance_m), impl_(std::make_unique<Impl>()) {
  const double max_voxels = max_distance_m_ / map.voxelSize();
  impl_->max_dist2 = static_cast<float>(max_voxels * max_voxels);
}

DistanceField::~DistanceField() = default;

void DistanceField::update(const MapDelta& delta) {
  std::unique_lock<detail::FairSharedMutex> lock(mutex_);
  {
    const auto acc = map_.constAccessor();
    BlockView view;
    for (const BlockIndex& block : delta.changed_blocks) {
      acc.readBlock(block, view);
      for (int o = 0; o < kBlockVoxels; ++o) {
        const bool known = (view.known[o >> 6] >> (o & 63)) & 1;
        const bool occupied = known && map_.model().isOccupied(view.log_odds[o]);
        const VoxelIndex ijk = voxelOfOffset(block, o);
        const Cell* c = impl_->find(ijk);
        const bool was = c != nullptr && c->is_obstacle;
        if (occupied && !was) impl_->setObstacle(ijk);
        if (!occupied && was) impl_->removeObstacle(ijk);
      }
    }
  }
  impl_->propagate();
}

void DistanceField::rebuild() {
  {
    std::unique_lock<detail::FairSharedMutex> lock(mutex_);
    impl_->blocks.clear();
  }
  MapDelta all;
  all.changed_blocks = map_.constAccessor().knownBlocks();
  update(all);
}

double DistanceField::voxelDistance(const VoxelIndex& ijk) const {
  std::shared_lock<detail::FairSharedMutex> lock(mutex_);
  const Cell* c = impl_->find(ijk);
  if (c == nullptr || !c->hasObstacle()) return max_distance_m_;
  return std::min(max_distance_m_, std::sqrt(static_cast<double>(c->dist2)) * map_.voxelSize());
}

std::vector<DistanceQuery> DistanceField::query(const std::vector<Eigen::Vector3d>& points_m) const {
  std::shared_lock<detail::FairSharedMutex> lock(mutex_);
  std::vector<DistanceQuery> out(points_m.size());
  const double s = map_.voxelSize();
  for (size_t i = 0; i < points_m.size(); ++i) {
    DistanceQuery& q = out[i];
    q.distance_m = max_distance_m_;
    const Eigen::Vector3d& p = points_m[i];
    if (!p.allFinite() || (p.array().abs() > 1e9 * s).any()) continue;
    const Cell* c = impl_->find(toVoxel(p, s));
    if (c == nullptr || !c->hasObstacle()) continue;
    const Eigen::Vector3d away = p - voxelCentre(c->obstacle, s);
    const double d = away.norm();
    if (d >= max_distance_m_) continue;
    q.distance_m = d;
    q.within_max = true;
    if (d > 0.0) q.gradient = away / d;
  }
  return out;
}

size_t DistanceField::numBlocks() const {
  std::shared_lock<detail::FairSharedMutex> lock(mutex_);
  return impl_->blocks.size();
}

}  // namespace cenote::mapping
