#include "mapping/distance/distance_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
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

struct Block {
  std::array<Cell, kBlockVoxels> cells;
  std::array<uint64_t, 8> obstacle{};  // bit offsetInBlock: occupied in the map as last seen
};

// Cells waiting to spread, first in first out. The waves are label-correcting (a cell lowered
// twice spreads twice), so any order reaches the same field; breadth-first order keeps
// consecutive cells next to each other in memory, where ordering by distance (Lau et al.'s
// priority queue) jumps across the whole wave front between pops and waited on cache misses.
class WaveQueue {
 public:
  void push(int key, const VoxelIndex& ijk) { entries_.push_back({ijk, key}); }
  bool empty() const { return head_ == entries_.size(); }
  VoxelIndex pop(int& key) {
    const Entry& e = entries_[head_++];
    key = e.key;
    const VoxelIndex ijk = e.ijk;
    if (head_ == entries_.size()) {
      entries_.clear();
      head_ = 0;
    }
    return ijk;
  }

 private:
  struct Entry {
    VoxelIndex ijk;
    int key;  // squared distance when pushed (raise: the old one)
  };
  std::vector<Entry> entries_;
  size_t head_ = 0;
};

}  // namespace

struct DistanceField::Impl {
  detail::BlockTable table;                   // block -> index in blocks (blocks are never freed)
  std::vector<std::unique_ptr<Block>> blocks;
  WaveQueue open;
  int max_dist2 = 0;
  // One-block cache for the neighbour walks: most neighbours share the popped cell's block.
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
    cached_index = b;
    cached = blocks.back().get();
    return *cached;
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

  void setObstacle(Block& block, const BlockIndex& b, int o) {
    block.obstacle[o >> 6] |= 1ull << (o & 63);
    Cell& c = block.cells[o];
    c.dx = c.dy = c.dz = 0;
    c.raise = 0;
    open.push(0, voxelOfOffset(b, o));
  }
  void removeObstacle(Block& block, const BlockIndex& b, int o) {
    removed_any = true;
    block.obstacle[o >> 6] &= ~(1ull << (o & 63));
    Cell& c = block.cells[o];
    c.clear();
    c.raise = 1;
    open.push(0, voxelOfOffset(b, o));
  }

  // The 27 blocks around the block of the cell being spread (most neighbours of a cell lie in its
  // own block, the rest in these): looked up once per centre block instead of once per neighbour.
  struct Neighbourhood {
    BlockIndex centre = BlockIndex::Constant(std::numeric_limits<int>::min());
    std::array<Block*, 27> blocks{};
    std::array<bool, 27> looked_up{};
  } around;
  bool removed_any = false;  // an obstacle went away in this update: lower entries must check theirs

  void moveAround(const BlockIndex& centre) {
    if (centre == around.centre) return;
    around.centre = centre;
    around.looked_up.fill(false);
  }
  // Block of the neighbour at block offset (bx, by, bz) in -1..1 from the centre; created if asked.
  Block* aroundBlock(int bx, int by, int bz, bool create) {
    const int i = (bx + 1) * 9 + (by + 1) * 3 + (bz + 1);
    if (!around.looked_up[i] || (create && around.blocks[i] == nullptr)) {
      const BlockIndex b = around.centre + BlockIndex(bx, by, bz);
      around.blocks[i] = create ? &getBlock(b) : findBlock(b);
      around.looked_up[i] = true;
    }
    return around.blocks[i];
  }

  // The raise and lower waves of Lau et al., in order of squared distance, over the 26 neighbours.
  void propagate() {
    while (!open.empty()) {
      int key;
      const VoxelIndex ijk = open.pop(key);
      moveAround(blockOf(ijk));
      Block* centre = aroundBlock(0, 0, 0, false);
      if (centre == nullptr) continue;
      Cell* c = &centre->cells[offsetInBlock(ijk)];
      const int lx = ijk.x() & 7, ly = ijk.y() & 7, lz = ijk.z() & 7;
      if (c->raise) {
        c->raise = 0;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              if (dx == 0 && dy == 0 && dz == 0) continue;
              Block* nb = aroundBlock((lx + dx) >> 3, (ly + dy) >> 3, (lz + dz) >> 3, false);
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
                open.push(old, n);
              } else {
                // Still valid: re-spreads into the cleared region.
                open.push(nc->dist2(), n);
              }
            }
        continue;
      }
      if (!c->hasObstacle() || key > c->dist2()) continue;  // stale entry
      const VoxelIndex to_obstacle(c->dx, c->dy, c->dz);
      if (removed_any && !isObstacle(ijk + to_obstacle)) continue;  // a raise will clear it
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            if (std::abs(dx) + std::abs(dy) + std::abs(dz) != 1) continue;
            const VoxelIndex offset = to_obstacle - VoxelIndex(dx, dy, dz);  // from the neighbour
            const int d2 = offset.squaredNorm();
            if (d2 > max_dist2) continue;
            Block* nb = aroundBlock((lx + dx) >> 3, (ly + dy) >> 3, (lz + dz) >> 3, true);
            Cell& nc = nb->cells[(((lx + dx) & 7) << 6) | (((ly + dy) & 7) << 3) | ((lz + dz) & 7)];
            if (nc.raise || (nc.hasObstacle() && d2 >= nc.dist2())) continue;
            nc.dx = static_cast<int16_t>(offset.x());
            nc.dy = static_cast<int16_t>(offset.y());
            nc.dz = static_cast<int16_t>(offset.z());
            open.push(d2, ijk + VoxelIndex(dx, dy, dz));
          }
    }
    removed_any = false;
  }
};

DistanceField::DistanceField(const OccupancyMap& map)
    : map_(map), impl_(std::make_unique<Impl>()) {
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
            impl_->setObstacle(*block, b, w * 64 + bit);
          } else {
            impl_->removeObstacle(*block, b, w * 64 + bit);
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
    impl_->around = Impl::Neighbourhood{};
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
