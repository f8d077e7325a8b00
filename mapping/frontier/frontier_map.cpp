#include "mapping/frontier/frontier_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <deque>
#include <limits>
#include <mutex>
#include <unordered_map>

#include "mapping/detail/block_table.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

using Mask = std::array<uint64_t, 8>;  // one bit per voxel of a block, bit offsetInBlock(ijk)

const VoxelIndex kFaces[6] = {VoxelIndex(1, 0, 0),  VoxelIndex(-1, 0, 0), VoxelIndex(0, 1, 0),
                              VoxelIndex(0, -1, 0), VoxelIndex(0, 0, 1),  VoxelIndex(0, 0, -1)};
const BlockIndex kBlockFaces[6] = {BlockIndex(1, 0, 0),  BlockIndex(-1, 0, 0), BlockIndex(0, 1, 0),
                                   BlockIndex(0, -1, 0), BlockIndex(0, 0, 1),  BlockIndex(0, 0, -1)};

bool testBit(const Mask& m, int o) { return (m[o >> 6] >> (o & 63)) & 1; }

struct FrontierVoxel {
  VoxelIndex ijk;
  uint8_t faces;  // unknown face neighbours, bit i: kFaces[i]
};

struct Component {
  std::vector<FrontierVoxel> voxels;
  std::vector<FrontierCluster> clusters;
};

// Frontier bits of one block and the component of each frontier voxel.
struct FrontierBlock {
  Mask frontier{};
  std::array<uint32_t, kBlockVoxels> component{};  // meaningful where frontier is set; 0 = unassigned
  std::array<uint8_t, kBlockVoxels> faces{};       // unknown face neighbours (frontierMask)
};

// The map's voxel states in a block as this frontier map last saw them: a block whose states did
// not change (only log-odds moved) changes no frontier.
struct StateSnapshot {
  Mask known{}, occupied{};
};

// Known / occupied masks of the map's blocks, read once per update through the accessor.
class MaskCache {
 public:
  explicit MaskCache(const OccupancyMap::ConstAccessor& acc) : acc_(acc) {}
  const Mask& known(const BlockIndex& b) { return entry(b).known; }
  const Mask& occupied(const BlockIndex& b) { return entry(b).occupied; }

 private:
  struct Entry {
    Mask known, occupied;
  };
  Entry& entry(const BlockIndex& b) {
    if (last_ != nullptr && b == last_block_) return *last_;
    bool inserted;
    const uint32_t slot = table_.findOrInsert(detail::packIndex(b), inserted);
    if (inserted) {
      entries_.emplace_back();
      acc_.readBlockMasks(b, entries_.back().known, entries_.back().occupied);
    }
    last_block_ = b;
    last_ = &entries_[slot];
    return *last_;
  }
  const OccupancyMap::ConstAccessor& acc_;
  detail::BlockTable table_;
  std::deque<Entry> entries_;  // references stay valid as it grows
  BlockIndex last_block_;
  Entry* last_ = nullptr;
};

// Unit direction into the unknown of a voxel whose unknown face neighbours are the set bits of
// `faces` (bit i: kFaces[i]); zero when none.
Eigen::Vector3d faceDirection(uint8_t faces) {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (int i = 0; i < 6; ++i) {
    if ((faces >> i) & 1) d += kFaces[i].cast<double>();
  }
  const double n = d.norm();
  return n > 0.0 ? Eigen::Vector3d(d / n) : d;
}

// Frontier voxels of a block: free (known, not occupied) with an unknown face neighbour; and for
// each, its unknown faces (bit i: kFaces[i]). Words are x slices (word = x), bits y * 8 + z; a
// neighbour across the block's face comes from the neighbouring block's facing layer.
Mask frontierMask(MaskCache& masks, const BlockIndex& b, std::array<uint8_t, kBlockVoxels>& faces) {
  Mask free_bits;
  const Mask& k = masks.known(b);
  bool any = false;
  for (int w = 0; w < 8; ++w) {
    free_bits[w] = k[w] & ~masks.occupied(b)[w];
    any |= free_bits[w] != 0;
  }
  Mask out{};
  if (!any) return out;
  const Mask& kxp = masks.known(b + kBlockFaces[0]);
  const Mask& kxm = masks.known(b + kBlockFaces[1]);
  const Mask& kyp = masks.known(b + kBlockFaces[2]);
  const Mask& kym = masks.known(b + kBlockFaces[3]);
  const Mask& kzp = masks.known(b + kBlockFaces[4]);
  const Mask& kzm = masks.known(b + kBlockFaces[5]);
  constexpr uint64_t kZ0 = 0x0101010101010101ull, kZ7 = kZ0 << 7;
  for (int w = 0; w < 8; ++w) {
    // Known bits of each face neighbour, in the order of kFaces.
    const uint64_t known_at[6] = {
        w < 7 ? k[w + 1] : kxp[0],
        w > 0 ? k[w - 1] : kxm[7],
        (k[w] >> 8) | ((kyp[w] & 0xFFull) << 56),
        (k[w] << 8) | (kym[w] >> 56),
        ((k[w] >> 1) & ~kZ7) | ((kzp[w] & kZ0) << 7),
        ((k[w] << 1) & ~kZ0) | ((kzm[w] & kZ7) >> 7),
    };
    out[w] = free_bits[w] & ~(known_at[0] & known_at[1] & known_at[2] & known_at[3] & known_at[4] & known_at[5]);
    uint64_t bits = out[w];
    while (bits != 0) {
      const int bit = __builtin_ctzll(bits);
      bits &= bits - 1;
      uint8_t f = 0;
      for (int i = 0; i < 6; ++i) f |= static_cast<uint8_t>(((~known_at[i] >> bit) & 1) << i);
      faces[w * 64 + bit] = f;
    }
  }
  return out;
}

}  // namespace

struct FrontierMap::Impl {
  std::optional<Aabb> roi;
  detail::BlockTable state_table;  // block -> index in states
  std::deque<StateSnapshot> states;
  detail::BlockTable table;  // block -> index in blocks (never freed; a block may become empty)
  std::vector<std::unique_ptr<FrontierBlock>> blocks;
  std::unordered_map<uint32_t, Component> components;
  uint32_t next_component = 1;
  uint64_t next_cluster = 1;
  size_t num_frontier = 0;
  int min_voxels = 10;
  double max_extent_m = 2.0;
  double s = 0.05;

  FrontierBlock* findBlock(const BlockIndex& b) const {
    const uint32_t slot = table.find(detail::packIndex(b));
    return slot == detail::BlockTable::kNone ? nullptr : blocks[slot].get();
  }
  FrontierBlock& getBlock(const BlockIndex& b) {
    bool inserted;
    const uint32_t slot = table.findOrInsert(detail::packIndex(b), inserted);
    if (inserted) blocks.push_back(std::make_unique<FrontierBlock>());
    return *blocks[slot];
  }

  // Frontier mask of a block with the region of interest applied.
  Mask frontierInRoi(MaskCache& masks, const BlockIndex& b, std::array<uint8_t, kBlockVoxels>& faces) const {
    if (roi) {
      Aabb box;
      box.min_m = (b * kBlockSide).cast<double>() * s;
      box.max_m = ((b * kBlockSide).array() + kBlockSide).cast<double>().matrix() * s;
      if ((box.max_m.array() < roi->min_m.array()).any() || (box.min_m.array() > roi->max_m.array()).any()) return Mask{};
    }
    Mask m = frontierMask(masks, b, faces);
    if (!roi) return m;
    for (int w = 0; w < 8; ++w) {
      uint64_t bits = m[w];
      while (bits != 0) {
        const int bit = __builtin_ctzll(bits);
        bits &= bits - 1;
        if (!roi->contains(voxelCentre(voxelOfOffset(b, w * 64 + bit), s))) m[w] &= ~(1ull << bit);
      }
    }
    return m;
  }

  // Splits voxels along their main axis until small enough; appends clusters of >= min_voxels.
  void split(std::vector<FrontierVoxel> voxels, std::vector<FrontierCluster>& out) {
    if (static_cast<int>(voxels.size()) < min_voxels) return;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    VoxelBox box;
    for (const auto& v : voxels) {
      mean += voxelCentre(v.ijk, s);
      box.extend(v.ijk);
    }
    mean /= static_cast<double>(voxels.size());
    const double extent_m = ((box.max - box.min).cast<double>().array() + 1.0).maxCoeff() * s;
    if (extent_m > max_extent_m && voxels.size() >= 2) {
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const auto& v : voxels) {
        const Eigen::Vector3d d = voxelCentre(v.ijk, s) - mean;
        cov += d * d.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      const Eigen::Vector3d axis = eig.eigenvectors().col(2);
      std::vector<FrontierVoxel> a, b;
      for (const auto& v : voxels) ((voxelCentre(v.ijk, s) - mean).dot(axis) < 0.0 ? a : b).push_back(v);
      if (!a.empty() && !b.empty()) {
        split(std::move(a), out);
        split(std::move(b), out);
        return;
      }
    }
    FrontierCluster c;
    c.id = next_cluster++;
    c.num_voxels = voxels.size();
    c.centroid_m = mean;
    c.bounds_m.min_m = box.min.cast<double>() * s;
    c.bounds_m.max_m = (box.max.cast<double>().array() + 1.0).matrix() * s;
    for (const auto& v : voxels) c.direction += faceDirection(v.faces);
    if (c.direction.norm() > 0.0) c.direction.normalize();
    out.push_back(c);
  }

  // The component label of a frontier voxel, or nullptr when v is not a frontier voxel. Caches
  // the 27 blocks around the last block asked for: a flood fill's neighbours lie in them.
  struct LabelCursor {
    const Impl& impl;
    BlockIndex centre = BlockIndex::Zero();
    bool has_centre = false;
    std::array<FrontierBlock*, 27> around{};
    std::array<bool, 27> looked_up{};
    uint8_t faces = 0;  // of the voxel last found by at()

    uint32_t* at(const VoxelIndex& v) {
      const BlockIndex b = blockOf(v);
      if (!has_centre || ((b - centre).array().abs() > 1).any()) {
        centre = b;
        has_centre = true;
        looked_up.fill(false);
      }
      const BlockIndex r = b - centre;
      const int i = (r.x() + 1) * 9 + (r.y() + 1) * 3 + (r.z() + 1);
      if (!looked_up[i]) {
        around[i] = impl.findBlock(b);
        looked_up[i] = true;
      }
      FrontierBlock* fb = around[i];
      if (fb == nullptr) return nullptr;
      const int o = offsetInBlock(v);
      if (!testBit(fb->frontier, o)) return nullptr;
      faces = fb->faces[o];
      return &fb->component[o];
    }
  };

  // Re-examines `blocks` and their face neighbours (whose boundary voxels see the changed ones).
  void apply(const OccupancyMap& map, const std::vector<BlockIndex>& changed) {
    const auto acc = map.constAccessor();
    MaskCache masks(acc);
    // 1. The region: changed blocks and their face neighbours, each once.
    detail::BlockTable seen;
    std::vector<BlockIndex> region;
    auto addBlock = [&](const BlockIndex& b) {
      bool inserted;
      seen.findOrInsert(detail::packIndex(b), inserted);
      if (inserted) region.push_back(b);
    };
    for (const BlockIndex& b : changed) {
      bool inserted;
      const uint32_t slot = state_table.findOrInsert(detail::packIndex(b), inserted);
      if (inserted) states.emplace_back();
      StateSnapshot& before = states[slot];
      if (before.known == masks.known(b) && before.occupied == masks.occupied(b)) continue;
      before.known = masks.known(b);
      before.occupied = masks.occupied(b);
      addBlock(b);
      for (const BlockIndex& f : kBlockFaces) addBlock(b + f);
    }
    // 2. New frontier masks; components that lose or keep voxels here are rebuilt (a removed
    // voxel may split its component, and a kept one's direction into the unknown may change).
    std::vector<uint32_t> dirty;
    std::vector<VoxelIndex> seeds;
    std::array<uint8_t, kBlockVoxels> faces;
    for (const BlockIndex& b : region) {
      const Mask now = frontierInRoi(masks, b, faces);
      FrontierBlock* fb = findBlock(b);
      if (fb == nullptr) {
        if (std::all_of(now.begin(), now.end(), [](uint64_t w) { return w == 0; })) continue;
        fb = &getBlock(b);
      }
      for (int w = 0; w < 8; ++w) {
        uint64_t old_bits = fb->frontier[w];
        num_frontier -= static_cast<size_t>(__builtin_popcountll(old_bits));
        num_frontier += static_cast<size_t>(__builtin_popcountll(now[w]));
        while (old_bits != 0) {
          const int bit = __builtin_ctzll(old_bits);
          old_bits &= old_bits - 1;
          const uint32_t id = fb->component[w * 64 + bit];
          if (id != 0 && (dirty.empty() || dirty.back() != id)) dirty.push_back(id);
        }
        uint64_t new_bits = now[w] & ~fb->frontier[w];
        fb->frontier[w] = now[w];
        uint64_t kept = now[w];
        while (kept != 0) {
          const int bit = __builtin_ctzll(kept);
          kept &= kept - 1;
          fb->faces[w * 64 + bit] = faces[w * 64 + bit];
        }
        while (new_bits != 0) {
          const int bit = __builtin_ctzll(new_bits);
          new_bits &= new_bits - 1;
          fb->component[w * 64 + bit] = 0;
          seeds.push_back(voxelOfOffset(b, w * 64 + bit));
        }
      }
    }
    std::sort(dirty.begin(), dirty.end());
    dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
    LabelCursor cursor{*this};
    for (uint32_t id : dirty) {
      auto it = components.find(id);
      if (it == components.end()) continue;
      for (const auto& v : it->second.voxels) {
        if (uint32_t* label = cursor.at(v.ijk)) {
          *label = 0;
          seeds.push_back(v.ijk);
        }
      }
      components.erase(it);
    }
    // 3. Flood fill (26-connected) from the seeds; an untouched component reached on the way is
    // absorbed into the new one.
    std::vector<FrontierVoxel> stack;
    LabelCursor near{*this};
    for (const VoxelIndex& seed : seeds) {
      uint32_t* seed_label = cursor.at(seed);
      if (seed_label == nullptr || *seed_label != 0) continue;
      const uint32_t id = next_component++;
      Component comp;
      *seed_label = id;
      stack.assign(1, {seed, cursor.faces});
      while (!stack.empty()) {
        const FrontierVoxel fv = stack.back();
        stack.pop_back();
        comp.voxels.push_back(fv);
        const VoxelIndex& v = fv.ijk;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              const VoxelIndex n = v + VoxelIndex(dx, dy, dz);
              uint32_t* label = near.at(n);
              if (label == nullptr || *label == id) continue;
              if (*label != 0) {
                auto old = components.find(*label);
                if (old != components.end()) {
                  LabelCursor other{*this};
                  for (const auto& w : old->second.voxels) {
                    uint32_t* wl = other.at(w.ijk);
                    if (wl != nullptr && *wl == old->first) *wl = 0;
                  }
                  components.erase(old);
                }
              }
              *label = id;
              stack.push_back({n, near.faces});
            }
      }
      split(comp.voxels, comp.clusters);
      components.emplace(id, std::move(comp));
    }
  }
};

FrontierMap::FrontierMap(const OccupancyMap& map, std::optional<Aabb> region_of_interest_m)
    : map_(map), impl_(std::make_unique<Impl>()) {
  impl_->roi = region_of_interest_m;
  impl_->min_voxels = map.config().frontier_min_voxels;
  impl_->max_extent_m = map.config().frontier_max_extent_m;
  impl_->s = map.voxelSize();
}

FrontierMap::~FrontierMap() = default;

void FrontierMap::update(const MapDelta& delta) {
  std::unique_lock<detail::FairSharedMutex> lock(mutex_);
  impl_->apply(map_, delta.changed_blocks);
}

void FrontierMap::rebuild() {
  std::unique_lock<detail::FairSharedMutex> lock(mutex_);
  impl_->table.clear();
  impl_->blocks.clear();
  impl_->state_table.clear();
  impl_->states.clear();
  impl_->components.clear();
  impl_->num_frontier = 0;
  // Own statement: the temporary accessor's shared lock must be gone before apply() takes one.
  const std::vector<BlockIndex> known = map_.constAccessor().knownBlocks();
  impl_->apply(map_, known);
}

std::vector<FrontierCluster> FrontierMap::clusters(const Eigen::Vector3d& position_m) const {
  std::shared_lock<detail::FairSharedMutex> lock(mutex_);
  std::vector<FrontierCluster> out;
  for (const auto& [id, comp] : impl_->components) {
    for (FrontierCluster c : comp.clusters) {
      c.distance_m = (c.centroid_m - position_m).norm();
      out.push_back(c);
    }
  }
  std::sort(out.begin(), out.end(), [](const FrontierCluster& a, const FrontierCluster& b) {
    return a.distance_m != b.distance_m ? a.distance_m < b.distance_m : a.id < b.id;
  });
  return out;
}

size_t FrontierMap::numFrontierVoxels() const {
  std::shared_lock<detail::FairSharedMutex> lock(mutex_);
  return impl_->num_frontier;
}

}  // namespace cenote::mapping
