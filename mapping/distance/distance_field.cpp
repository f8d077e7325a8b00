#include "mapping/distance/distance_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <mutex>

#include "mapping/detail/block_table.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

// The constructor limits max_distance_m to this many voxels (50 m at 5 cm), so that offsets to the
// nearest obstacle fit int16 and squared distances an int.
constexpr int kMaxOffsetVoxels = 1000;

// One voxel of the field: the offset from it to its nearest obstacle voxel (none: kNoObstacle).
// The squared distance is the offset's squared norm, so a cell is 8 bytes.
struct Cell {
  static constexpr int16_t kNoObstacle = INT16_MIN;
  int16_t dx = kNoObstacle, dy = 0, dz = 0;
  uint8_t raise = 0;  // queued to clear (its obstacle went away)
  bool hasObstacle() const { return dx != kNoObstacle; }
  int dist2() const { return dx * dx + dy * dy + dz * dz; }
  void clear() { dx = kNoObstacle; }
};

// A face neighbour of a cell: one step along one axis; `stride` is that axis's step of offsetInBlock.
struct Face {
  int axis, step, stride;
};
// In the order of the lower wave's original (dx, dy, dz) loops, which the field depends on (ties).
constexpr std::array<Face, 6> kFaces = {{{0, -1, 64}, {1, -1, 8}, {2, -1, 1}, {2, 1, 1}, {1, 1, 8}, {0, 1, 64}}};

// Index in Block::around of the block at block offset (bx, by, bz), each in -1..1.
constexpr int aroundSlot(int bx, int by, int bz) { return (bx + 1) * 9 + (by + 1) * 3 + (bz + 1); }

struct Block {
  std::array<Cell, kBlockVoxels> cells;
  std::array<uint64_t, 8> obstacle{};  // bit offsetInBlock: occupied in the map as last seen
  BlockIndex index = BlockIndex::Zero();
  // The 27 blocks around this one (itself in the middle; nullptr: not created), linked both ways
  // when a block is created: the waves step to neighbour cells without a hash lookup.
  std::array<Block*, 27> around{};
};

// Cells waiting to spread, first in first out. The waves are label-correcting (a cell lowered
// twice spreads twice), so any order reaches the same field; breadth-first order keeps
// consecutive cells next to each other in memory, where ordering by distance (Lau et al.'s
// priority queue) jumps across the whole wave front between pops and waited on cache misses.
class WaveQueue {
 public:
  struct Entry {
    Block* block;
    int key;     // squared distance when pushed (raise: the old one)
    int offset;  // offsetInBlock
  };
  void push(int key, Block* block, int offset) { entries_.push_back({block, key, offset}); }
  bool empty() const { return head_ == entries_.size(); }
  Entry pop() {
    const Entry e = entries_[head_++];
    if (head_ == entries_.size()) {
      entries_.clear();
      head_ = 0;
    }
    return e;
  }

 private:
  std::vector<Entry> entries_;
  size_t head_ = 0;
};

}  // namespace

struct DistanceField::Impl {
  detail::BlockTable table;  // block -> index in blocks (blocks are never freed)
  std::vector<std::unique_ptr<Block>> blocks;
  WaveQueue open;
  int max_dist2 = 0;
  // One-block cache for the obstacle checks and the changed blocks (the waves use Block::around).
  BlockIndex cached_index = BlockIndex::Constant(INT32_MIN);
  Block* cached = nullptr;

  Block* findBlock(const BlockIndex& b) {
    if (b == cached_index) return cached;
    const uint32_t slot = table.find(detail::packIndex(b));
    Block* block = slot == detail::BlockTable::kNone ? nullptr : blocks[slot].get();
    if (block != nullptr) {
      cached_index = b;
      cached = block;
    }
    return block;
  }
  const Block* findBlockConst(const BlockIndex& b) const {
    const uint32_t slot = table.find(detail::packIndex(b));
    return slot == detail::BlockTable::kNone ? nullptr : blocks[slot].get();
  }
  Block& getBlock(const BlockIndex& b) {
    if (Block* block = findBlock(b)) return *block;
    bool inserted;
    table.findOrInsert(detail::packIndex(b), inserted);
    blocks.push_back(std::make_unique<Block>());
    Block* block = blocks.back().get();
    block->index = b;
    link(*block);
    cached_index = b;
    cached = block;
    return *block;
  }
  // Links a new block and the existing blocks around it to each other.
  void link(Block& block) {
    for (int bx = -1; bx <= 1; ++bx)
      for (int by = -1; by <= 1; ++by)
        for (int bz = -1; bz <= 1; ++bz) {
          const int i = aroundSlot(bx, by, bz);
          if (i == aroundSlot(0, 0, 0)) {
            block.around[i] = &block;
            continue;
          }
          const uint32_t slot = table.find(detail::packIndex(block.index + BlockIndex(bx, by, bz)));
          if (slot == detail::BlockTable::kNone) continue;
          Block* other = blocks[slot].get();
          block.around[i] = other;
          other->around[aroundSlot(-bx, -by, -bz)] = &block;
        }
  }
  Cell* find(const VoxelIndex& ijk) {
    Block* block = findBlock(blockOf(ijk));
    return block == nullptr ? nullptr : &block->cells[offsetInBlock(ijk)];
  }
  const Cell* findConst(const VoxelIndex& ijk) const {
    const Block* block = findBlockConst(blockOf(ijk));
    return block == nullptr ? nullptr : &block->cells[offsetInBlock(ijk)];
  }
  bool isObstacle(const VoxelIndex& ijk) {
    const Block* block = findBlock(blockOf(ijk));
    if (block == nullptr) return false;
    const int o = offsetInBlock(ijk);
    return (block->obstacle[o >> 6] >> (o & 63)) & 1;
  }

  void setObstacle(Block& block, int o) {
    block.obstacle[o >> 6] |= 1ull << (o & 63);
    Cell& c = block.cells[o];
    c.dx = c.dy = c.dz = 0;
    c.raise = 0;
    open.push(0, &block, o);
  }
  void removeObstacle(Block& block, int o) {
    removed_any = true;
    block.obstacle[o >> 6] &= ~(1ull << (o & 63));
    Cell& c = block.cells[o];
    c.clear();
    c.raise = 1;
    open.push(0, &block, o);
  }

  bool removed_any = false;  // an obstacle went away in this update: lower entries must check theirs

  // Block of the neighbour at block offset (bx, by, bz) in -1..1 from `centre`, created if asked.
  Block* aroundBlock(Block& centre, int bx, int by, int bz, bool create) {
    Block* block = centre.around[aroundSlot(bx, by, bz)];
    if (block == nullptr && create) block = &getBlock(centre.index + BlockIndex(bx, by, bz));
    return block;
  }

  // The raise and lower waves of Lau et al., in order of squared distance, over the 26 neighbours.
  void propagate() {
    while (!open.empty()) {
      const WaveQueue::Entry e = open.pop();
      const int key = e.key;
      Block& centre = *e.block;
      const VoxelIndex ijk = voxelOfOffset(centre.index, e.offset);
      Cell* c = &centre.cells[e.offset];
      const int lx = e.offset >> 6, ly = (e.offset >> 3) & 7, lz = e.offset & 7;
      if (c->raise) {
        c->raise = 0;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              if (dx == 0 && dy == 0 && dz == 0) continue;
              Block* nb = aroundBlock(centre, (lx + dx) >> 3, (ly + dy) >> 3, (lz + dz) >> 3, false);
              if (nb == nullptr) continue;
              const int no = (((lx + dx) & 7) << 6) | (((ly + dy) & 7) << 3) | ((lz + dz) & 7);
              Cell* nc = &nb->cells[no];
              if (!nc->hasObstacle() || nc->raise) continue;
              const VoxelIndex n = ijk + VoxelIndex(dx, dy, dz);
              const VoxelIndex obstacle = n + VoxelIndex(nc->dx, nc->dy, nc->dz);
              if (!isObstacle(obstacle)) {
                // Pointed at a removed obstacle: clear it and spread the raise.
                const int old = nc->dist2();
                nc->clear();
                nc->raise = 1;
                open.push(old, nb, no);
              } else {
                // Still valid: re-spreads into the cleared region.
                open.push(nc->dist2(), nb, no);
              }
            }
        continue;
      }
      if (!c->hasObstacle() || key > c->dist2()) continue;  // stale entry
      const VoxelIndex to_obstacle(c->dx, c->dy, c->dz);
      if (removed_any && !isObstacle(ijk + to_obstacle)) continue;  // a raise will clear it
      // The 6 face neighbours, in the order of the original (dx, dy, dz) loops.
      const int local[3] = {lx, ly, lz};
#pragma GCC unroll 6  // constant faces: the axis and stride fold into each copy
      for (const Face& f : kFaces) {
        VoxelIndex offset = to_obstacle;  // from the neighbour
        offset[f.axis] -= f.step;
        const int d2 = offset.squaredNorm();
        if (d2 > max_dist2) continue;
        const bool inside = static_cast<unsigned>(local[f.axis] + f.step) < kBlockSide;
        Block* nb = &centre;
        if (!inside) {
          BlockIndex step = BlockIndex::Zero();
          step[f.axis] = f.step;
          nb = aroundBlock(centre, step.x(), step.y(), step.z(), true);
        }
        const int no = e.offset + (inside ? f.step : -f.step * (kBlockSide - 1)) * f.stride;
        Cell& nc = nb->cells[no];
        if (nc.raise || (nc.hasObstacle() && d2 >= nc.dist2())) continue;
        nc.dx = static_cast<int16_t>(offset.x());
        nc.dy = static_cast<int16_t>(offset.y());
        nc.dz = static_cast<int16_t>(offset.z());
        open.push(d2, nb, no);
      }
    }
    removed_any = false;
  }
};

DistanceField::DistanceField(const OccupancyMap& map) : map_(map), impl_(std::make_unique<Impl>()) {
  max_distance_m_ = std::min(map.config().max_distance_m, kMaxOffsetVoxels * map.voxelSize());
  // Squared distances are integers (voxels^2): d2 > floor(max^2) <=> d2 > max^2.
  impl_->max_dist2 = static_cast<int>(std::floor(std::pow(max_distance_m_ / map.voxelSize(), 2)));
}

DistanceField::~DistanceField() = default;

void DistanceField::update(const MapDelta& delta) {
  std::unique_lock<detail::FairSharedMutex> lock(mutex_);
  {
    const auto acc = map_.constAccessor();
    BlockView view;
    for (const BlockIndex& b : delta.changed_blocks) {
      acc.readBlock(b, view);
      std::array<uint64_t, 8> occupied{};
      for (int w = 0; w < 8; ++w) {
        uint64_t known = view.known[w];
        while (known != 0) {
          const int bit = __builtin_ctzll(known);
          known &= known - 1;
          if (map_.model().isOccupied(view.log_odds[w * 64 + bit])) occupied[w] |= 1ull << bit;
        }
      }
      Block* block = impl_->findBlock(b);
      if (block == nullptr) {
        if (std::all_of(occupied.begin(), occupied.end(), [](uint64_t w) { return w == 0; })) continue;
        block = &impl_->getBlock(b);
      }
      for (int w = 0; w < 8; ++w) {
        uint64_t changed = occupied[w] ^ block->obstacle[w];
        while (changed != 0) {
          const int bit = __builtin_ctzll(changed);
          changed &= changed - 1;
          if ((occupied[w] >> bit) & 1) {
            impl_->setObstacle(*block, w * 64 + bit);
          } else {
            impl_->removeObstacle(*block, w * 64 + bit);
          }
        }
      }
    }
  }
  impl_->propagate();
}

void DistanceField::rebuild() {
  {
    std::unique_lock<detail::FairSharedMutex> lock(mutex_);
    impl_->table.clear();
    impl_->blocks.clear();
    impl_->cached = nullptr;
    impl_->cached_index = BlockIndex::Constant(INT32_MIN);
  }
  MapDelta all;
  all.changed_blocks = map_.constAccessor().knownBlocks();
  update(all);
}

double DistanceField::voxelDistance(const VoxelIndex& ijk) const {
  std::shared_lock<detail::FairSharedMutex> lock(mutex_);
  const Cell* c = impl_->findConst(ijk);
  if (c == nullptr || !c->hasObstacle()) return max_distance_m_;
  return std::min(max_distance_m_, std::sqrt(static_cast<double>(c->dist2())) * map_.voxelSize());
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
    const VoxelIndex ijk = toVoxel(p, s);
    const Cell* c = impl_->findConst(ijk);
    if (c == nullptr || !c->hasObstacle()) continue;
    const VoxelIndex obstacle = ijk + VoxelIndex(c->dx, c->dy, c->dz);
    const Eigen::Vector3d away = p - voxelCentre(obstacle, s);
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
