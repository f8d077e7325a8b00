#include "mapping/frontier/frontier_map.h"

#include <algorithm>
#include <deque>
#include <mutex>
#include <unordered_map>

#include "mapping/detail/block_table.h"
#include "mapping/frontier/cluster_split.h"
#include "mapping/frontier/frontier_bits.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

using Mask = detail::BlockMask;  // one bit per voxel of a block, bit offsetInBlock(ijk)
using detail::kFaceOffsets;      // a voxel's face neighbours; the same offsets give a block's

// The 26 neighbour blocks' offsets.
const std::array<BlockIndex, 26> kNeighbourBlocks = [] {
  std::array<BlockIndex, 26> out;
  int i = 0;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z)
        if (x != 0 || y != 0 || z != 0) out[i++] = BlockIndex(x, y, z);
  return out;
}();

// A 26-connected piece of one block's frontier, and the component it belongs to.
// Fields in the order of use: joining reads the first cache line only, splitting the rest too.
struct Piece {
  uint32_t component = 0;     // 0: not yet assigned (during an update)
  uint32_t node = 0;          // its union-find node during an update
  detail::FaceLayers layers;  // of bits
  Mask bits{};
  detail::RunMoments moments;  // of bits
};

// Frontier bits of one block, their unknown faces, and their pieces.
// The small fields every step reads first, the faces (read where the frontier changed or a
// plane cuts a piece) last.
struct FrontierBlock {
  BlockIndex index;
  uint32_t mark = 0;  // update number that last queued it for labelling
  std::vector<Piece> pieces;
  std::array<uint32_t, 26> around;  // slots of the kNeighbourBlocks, BlockTable::kNone where none
  Mask frontier{};
  std::array<uint8_t, kBlockVoxels> faces{};  // unknown face neighbours where frontier, else 0
};

// A connected component of the frontier: the blocks holding its pieces, and its clusters.
struct Component {
  std::vector<uint32_t> blocks;  // slots, each once
  std::vector<FrontierCluster> clusters;
};

// The map's voxel states in a block as this frontier map last saw them: a block whose states did
// not change (only log-odds moved) changes no frontier.
struct StateSnapshot {
  Mask known{}, occupied{};
};

// Union-find over pieces, with path halving and union by index (the smaller root wins, so the
// result does not depend on the order of the unions).
class UnionFind {
 public:
  uint32_t add() {
    parent_.push_back(static_cast<uint32_t>(parent_.size()));
    return parent_.back();
  }
  uint32_t find(uint32_t i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];
      i = parent_[i];
    }
    return i;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a < b) parent_[b] = a;
    if (b < a) parent_[a] = b;
  }
  size_t size() const { return parent_.size(); }
  void clear() { parent_.clear(); }

 private:
  std::vector<uint32_t> parent_;
};

// Known / occupied masks of blocks during one update. A block some delta named comes from its
// snapshot: the update has just refreshed the snapshots of its own changed blocks, and a block no
// delta named since changed nothing (every change comes with a delta, given in order). Any other
// block is read from the map, once.
class MaskCache {
 public:
  // table: scratch kept for its capacity (cleared here).
  MaskCache(const OccupancyMap::ConstAccessor& acc, const detail::BlockTable& snapshot_table,
            const std::deque<StateSnapshot>& snapshots, detail::BlockTable& table)
      : acc_(acc), snapshot_table_(snapshot_table), snapshots_(snapshots), table_(table) {
    table_.clear();
  }
  // Valid for the whole update.
  const StateSnapshot& of(const BlockIndex& b) {
    if (last_ != nullptr && b == last_block_) return *last_;
    const uint64_t key = detail::packIndex(b);
    const uint32_t snapshot = snapshot_table_.find(key);
    if (snapshot != detail::BlockTable::kNone) {
      last_ = &snapshots_[snapshot];
    } else {
      bool inserted;
      const uint32_t slot = table_.findOrInsert(key, inserted);
      if (inserted) {
        entries_.emplace_back();
        acc_.readBlockMasks(b, entries_.back().known, entries_.back().occupied);
      }
      last_ = &entries_[slot];
    }
    last_block_ = b;
    return *last_;
  }

 private:
  const OccupancyMap::ConstAccessor& acc_;
  const detail::BlockTable& snapshot_table_;
  const std::deque<StateSnapshot>& snapshots_;
  detail::BlockTable& table_;          // blocks read from the map -> index in entries_
  std::deque<StateSnapshot> entries_;  // references stay valid as it grows
  BlockIndex last_block_;
  const StateSnapshot* last_ = nullptr;
};

// Frontier voxels of a block: free (known, not occupied) with an unknown face neighbour; and for
// each, its unknown faces (bit i: kFaceOffsets[i]) OR-ed into `faces`, which must be zero on entry.
// Words are x slices (word = x), bits y * 8 + z; a neighbour across the block's face comes from
// the neighbouring block's facing layer.
Mask frontierMask(MaskCache& masks, const BlockIndex& b, std::array<uint8_t, kBlockVoxels>& faces) {
  constexpr uint64_t kZ0 = detail::kLowBitOfEachByte, kZ7 = detail::kHighBitOfEachByte;
  Mask free_bits;
  const StateSnapshot& states = masks.of(b);
  const Mask& k = states.known;
  bool any = false;
  for (int w = 0; w < 8; ++w) {
    free_bits[w] = k[w] & ~states.occupied[w];
    any |= free_bits[w] != 0;
  }
  Mask out{};
  if (!any) return out;
  const Mask& kxp = masks.of(b + kFaceOffsets[0]).known;
  const Mask& kxm = masks.of(b + kFaceOffsets[1]).known;
  const Mask& kyp = masks.of(b + kFaceOffsets[2]).known;
  const Mask& kym = masks.of(b + kFaceOffsets[3]).known;
  const Mask& kzp = masks.of(b + kFaceOffsets[4]).known;
  const Mask& kzm = masks.of(b + kFaceOffsets[5]).known;
  for (int w = 0; w < 8; ++w) {
    // Known bits of each face neighbour, in the order of kFaceOffsets.
    const uint64_t known_at[6] = {
        w < 7 ? k[w + 1] : kxp[0],
        w > 0 ? k[w - 1] : kxm[7],
        (k[w] >> 8) | ((kyp[w] & 0xFFull) << 56),
        (k[w] << 8) | (kym[w] >> 56),
        ((k[w] >> 1) & ~kZ7) | ((kzp[w] & kZ0) << 7),
        ((k[w] << 1) & ~kZ0) | ((kzm[w] & kZ7) >> 7),
    };
    out[w] = free_bits[w] & ~(known_at[0] & known_at[1] & known_at[2] & known_at[3] & known_at[4] & known_at[5]);
    // Face by face: a frontier voxel has one or two unknown faces, rarely six.
    for (int i = 0; i < 6; ++i) {
      for (uint64_t bits = out[w] & ~known_at[i]; bits != 0; bits &= bits - 1) {
        faces[w * 64 + __builtin_ctzll(bits)] |= static_cast<uint8_t>(1 << i);
      }
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
  uint32_t update_number = 0;
  size_t num_frontier = 0;
  int min_voxels = 10;
  double max_extent_m = 2.0;
  double s = 0.05;
  // Scratch of one update, kept for its capacity: each update clears it instead of allocating it.
  detail::BlockTable region_table, read_table;
  std::vector<BlockIndex> region;       // changed blocks and their face neighbours, each once
  std::vector<uint8_t> inputs_changed;  // per region block: its states or a facing layer changed
  std::vector<uint32_t> relabel;        // blocks with unassigned frontier voxels
  std::vector<uint32_t> dirty;          // components taken apart
  std::vector<uint32_t> queued;         // blocks labelled this update, each once
  UnionFind sets;
  std::vector<std::pair<uint32_t, uint32_t>> nodes;  // union-find node -> (block slot, piece index)
  std::vector<Mask> new_pieces;
  std::vector<uint32_t> component_of_root;  // union-find root -> new component id
  std::vector<uint32_t> order;              // new component ids in creation order
  std::vector<detail::BlockRun> runs;       // a component's pieces

  uint32_t findSlot(const BlockIndex& b) const { return table.find(detail::packIndex(b)); }
  uint32_t getSlot(const BlockIndex& b) {
    bool inserted;
    const uint32_t slot = table.findOrInsert(detail::packIndex(b), inserted);
    if (inserted) {
      blocks.push_back(std::make_unique<FrontierBlock>());
      FrontierBlock& fb = *blocks.back();
      fb.index = b;
      // kNeighbourBlocks is symmetric: offset 25 - n is the opposite of offset n.
      for (int n = 0; n < 26; ++n) {
        fb.around[n] = findSlot(b + kNeighbourBlocks[n]);
        if (fb.around[n] != detail::BlockTable::kNone) blocks[fb.around[n]]->around[25 - n] = slot;
      }
    }
    return slot;
  }

  // Frontier mask of a block with the region of interest applied; faces zero where not frontier.
  Mask frontierInRoi(MaskCache& masks, const BlockIndex& b, std::array<uint8_t, kBlockVoxels>& faces) const {
    faces.fill(0);
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
        if (!roi->contains(voxelCentre(voxelOfOffset(b, w * 64 + bit), s))) {
          m[w] &= ~(1ull << bit);
          faces[w * 64 + bit] = 0;
        }
      }
    }
    return m;
  }

  // Takes the component `id` apart: its pieces become unassigned (their blocks are appended to
  // unassigned_blocks), its clusters go.
  void dissolve(uint32_t id, std::vector<uint32_t>& unassigned_blocks) {
    auto it = components.find(id);
    if (it == components.end()) return;
    for (uint32_t slot : it->second.blocks) {
      FrontierBlock& fb = *blocks[slot];
      for (Piece& p : fb.pieces) {
        if (p.component == id) p.component = 0;
      }
      unassigned_blocks.push_back(slot);
    }
    components.erase(it);
  }

  // Re-examines `changed` blocks whose voxel states changed, and their face neighbours (whose
  // boundary voxels see the changed ones); re-labels the components whose voxels changed.
  void apply(const OccupancyMap& map, const std::vector<BlockIndex>& changed) {
    const auto acc = map.constAccessor();
    ++update_number;
    // 1. The region: changed blocks and their face neighbours, each once. Only those whose
    // states changed, or whose neighbour's facing layer of known voxels changed, can have a new
    // frontier (the others are listed all the same: the order of the region fixes new ids).
    region_table.clear();
    region.clear();
    inputs_changed.clear();
    auto addBlock = [&](const BlockIndex& b, bool changed_inputs) {
      bool inserted;
      const uint32_t slot = region_table.findOrInsert(detail::packIndex(b), inserted);
      if (inserted) {
        region.push_back(b);
        inputs_changed.push_back(0);
      }
      inputs_changed[slot] |= static_cast<uint8_t>(changed_inputs);
    };
    StateSnapshot current;
    for (const BlockIndex& b : changed) {
      bool inserted;
      const uint32_t slot = state_table.findOrInsert(detail::packIndex(b), inserted);
      if (inserted) states.emplace_back();
      StateSnapshot& before = states[slot];
      acc.readBlockMasks(b, current.known, current.occupied);
      if (before.known == current.known && before.occupied == current.occupied) continue;
      // Face layer i of a block is the one its neighbour kFaceOffsets[i] sees.
      const detail::FaceLayers old_layers = detail::faceLayers(before.known);
      const detail::FaceLayers new_layers = detail::faceLayers(current.known);
      before = current;
      addBlock(b, true);
      for (int i = 0; i < 6; ++i) addBlock(b + kFaceOffsets[i], old_layers.layer[i] != new_layers.layer[i]);
    }
    MaskCache masks(acc, state_table, states, read_table);
    // 2. New frontier masks. A block whose frontier voxels or their faces changed loses its
    // pieces, and the components they belonged to are taken apart (a removed voxel may split one,
    // a changed face turns its direction).
    relabel.clear();
    dirty.clear();
    std::array<uint8_t, kBlockVoxels> faces;
    for (size_t r = 0; r < region.size(); ++r) {
      if (!inputs_changed[r]) continue;
      const BlockIndex& b = region[r];
      const Mask now = frontierInRoi(masks, b, faces);
      uint32_t slot = findSlot(b);
      if (slot == detail::BlockTable::kNone) {
        if (detail::isEmpty(now)) continue;
        slot = getSlot(b);
      }
      FrontierBlock& fb = *blocks[slot];
      if (fb.frontier == now && fb.faces == faces) continue;
      for (int w = 0; w < 8; ++w) {
        num_frontier -= static_cast<size_t>(__builtin_popcountll(fb.frontier[w]));
        num_frontier += static_cast<size_t>(__builtin_popcountll(now[w]));
      }
      fb.frontier = now;
      fb.faces = faces;
      for (const Piece& p : fb.pieces) dirty.push_back(p.component);
      fb.pieces.clear();
      relabel.push_back(slot);
    }
    std::sort(dirty.begin(), dirty.end());
    dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
    for (uint32_t id : dirty) dissolve(id, relabel);
    // 3. Pieces of the unassigned voxels of each block, a union-find node each.
    sets.clear();
    nodes.clear();
    queued.clear();
    for (uint32_t slot : relabel) {
      FrontierBlock& fb = *blocks[slot];
      if (fb.mark == update_number) continue;
      fb.mark = update_number;
      queued.push_back(slot);
      Mask unassigned = fb.frontier;
      for (const Piece& p : fb.pieces) {
        for (int w = 0; w < 8; ++w) unassigned[w] &= ~p.bits[w];
      }
      new_pieces.clear();
      detail::appendPieces(unassigned, new_pieces);
      for (const Mask& bits : new_pieces) {
        Piece p;
        p.bits = bits;
        p.layers = detail::faceLayers(bits);
        p.moments = detail::blockRunMoments(bits, fb.faces);
        fb.pieces.push_back(p);
      }
      for (uint32_t i = 0; i < fb.pieces.size(); ++i) {
        if (fb.pieces[i].component != 0) continue;
        fb.pieces[i].node = sets.add();
        nodes.emplace_back(slot, i);
      }
    }
    // 4. Join touching pieces across blocks. A piece of an untouched component that touches an
    // unassigned one is merged with it: that component is taken apart, its pieces joined at once
    // (they are connected).
    for (uint32_t slot : queued) {
      const std::array<uint32_t, 26>& around = blocks[slot]->around;
      for (uint32_t i = 0; i < blocks[slot]->pieces.size(); ++i) {
        const Piece& p = blocks[slot]->pieces[i];
        if (p.component != 0) continue;
        for (int n = 0; n < 26; ++n) {
          if (around[n] == detail::BlockTable::kNone) continue;
          FrontierBlock& nb = *blocks[around[n]];
          for (uint32_t j = 0; j < nb.pieces.size(); ++j) {
            if (!detail::piecesTouch(p.layers, nb.pieces[j].layers, kNeighbourBlocks[n])) continue;
            if (nb.pieces[j].component != 0) absorb(nb.pieces[j].component);
            sets.unite(p.node, nb.pieces[j].node);
          }
        }
      }
    }
    // 5. One component per set, in the order of their first piece; split into clusters.
    component_of_root.assign(sets.size(), 0);
    order.clear();
    for (uint32_t node = 0; node < nodes.size(); ++node) {
      const uint32_t root = sets.find(node);
      if (component_of_root[root] == 0) {
        component_of_root[root] = next_component++;
        order.push_back(component_of_root[root]);
        components.emplace(component_of_root[root], Component{});
      }
      const auto [slot, i] = nodes[node];
      FrontierBlock& fb = *blocks[slot];
      const uint32_t id = component_of_root[root];
      fb.pieces[i].component = id;
      std::vector<uint32_t>& comp_blocks = components[id].blocks;
      if (comp_blocks.empty() || comp_blocks.back() != slot) comp_blocks.push_back(slot);
    }
    for (uint32_t id : order) {
      Component& comp = components[id];
      std::sort(comp.blocks.begin(), comp.blocks.end());
      comp.blocks.erase(std::unique(comp.blocks.begin(), comp.blocks.end()), comp.blocks.end());
      runs.clear();
      for (uint32_t slot : comp.blocks) {
        const FrontierBlock& fb = *blocks[slot];
        for (const Piece& p : fb.pieces) {
          if (p.component == id) runs.push_back({fb.index, &p.bits, &fb.faces, &p.moments});
        }
      }
      const detail::SplitParams params{s, max_extent_m, min_voxels};
      detail::splitComponent(runs, params, next_cluster, comp.clusters);
    }
  }

  // Merges the untouched component `id` into this update's sets: its pieces get nodes, joined.
  void absorb(uint32_t id) {
    auto it = components.find(id);
    if (it == components.end()) return;
    uint32_t first = 0;
    bool has_first = false;
    for (uint32_t slot : it->second.blocks) {
      FrontierBlock& fb = *blocks[slot];
      for (uint32_t i = 0; i < fb.pieces.size(); ++i) {
        Piece& p = fb.pieces[i];
        if (p.component != id) continue;
        p.component = 0;
        p.node = sets.add();
        nodes.emplace_back(slot, i);
        if (has_first) sets.unite(first, p.node);
        first = has_first ? first : p.node;
        has_first = true;
      }
    }
    components.erase(it);
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
