#include "mapping/occupancy_map.h"

#include <openvdb/tools/Count.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/NodeManager.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include "common/error.h"
#include "mapping/detail/map_impl.h"
#include "mapping/detail/block_bits.h"
#include "mapping/detail/occupied_mask.h"
#include "mapping/detail/publish_word.h"
#include "mapping/integration/depth_frame.h"
#include "mapping/integration/voxel_ray.h"
#include "mapping/map_range.h"

namespace cenote::mapping {

namespace detail {

struct AccessorImpl {
  explicit AccessorImpl(const MapImpl& impl) : leaves(&impl.leaf_index), color(&impl.color) {}
  // The leaf holding ijk (nullptr: none); the last one is cached, as OpenVDB's accessors do
  // (neighbouring lookups, as in a segment walk, mostly fall into the same block).
  // The cache holds the block's packed key, not its BlockIndex: storing the three ints of a
  // BlockIndex made GCC load ijk's x and y as one 8-byte word, and callers write ijk as three 4-byte
  // stores (toIndex), which the CPU cannot forward to that load: it waited until the stores
  // retired, i.e. behind the previous lookup's cache misses, so lookups one call at a time ran one
  // after another instead of overlapping (16-17 M/s random lookups in map_bench; 28-33 with this).
  const LeafRef* leafAt(const VoxelIndex& ijk) {
    const BlockIndex block = blockOf(ijk);
    if (!inPackRange(block)) return nullptr;
    const uint64_t key = packIndex(block);
    if (key != last_key) {
      last_key = key;
      last = leaves->find(key);
    }
    return last;
  }
  // Log-odds of a voxel; false when unknown. Here, not in ConstAccessor::logOdds, so that state()
  // inlines it too (a call and a float through the stack per lookup otherwise).
  bool logOdds(const VoxelIndex& ijk, float& l) {
    const LeafRef* leaf = leafAt(ijk);
    return leaf != nullptr && leaf->logOdds(offsetInBlock(ijk), l);
  }
  const LeafIndex* leaves;
  const ColorStore* color;
  uint64_t last_key = ~0ull;  // no block packs to all ones
  const LeafRef* last = nullptr;
};

openvdb::math::Transform::Ptr makeTransform(double voxel_size_m) {
  auto transform = openvdb::math::Transform::createLinearTransform(voxel_size_m);
  transform->postTranslate(openvdb::Vec3d(0.5 * voxel_size_m));
  return transform;
}

}  // namespace detail

namespace {

using detail::blockOfFloatTreeOrderKey;
using detail::boxOfBits;
using detail::floatTreeOrderKey;
using detail::LeafIndex;
using detail::LeafRef;
using openvdb::Coord;

Coord coordOf(const VoxelIndex& ijk) { return Coord(ijk.x(), ijk.y(), ijk.z()); }

std::string formatPoint(const Eigen::Vector3d& p) {
  std::ostringstream text;
  text << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return text.str();
}

void initialiseOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Adds a changed block to a delta under construction (blocks arrive in any order; sorted later).
void noteChanged(MapDelta& delta, const BlockIndex& block, const VoxelBox& voxels, double s) {
  delta.changed_blocks.push_back(block);
  delta.changed_voxels.extend(voxels);
}

void finishDelta(MapDelta& delta, double s) {
  auto less = [](const BlockIndex& a, const BlockIndex& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(delta.changed_blocks.begin(), delta.changed_blocks.end(), less);
  delta.changed_blocks.erase(std::unique(delta.changed_blocks.begin(), delta.changed_blocks.end()),
                             delta.changed_blocks.end());
  if (!delta.changed_voxels.isEmpty()) {
    delta.changed_m.min_m = delta.changed_voxels.min.cast<double>() * s;
    delta.changed_m.max_m = (delta.changed_voxels.max.cast<double>().array() + 1.0).matrix() * s;
  }
}

}  // namespace

OccupancyMap::OccupancyMap(const MapConfig& config) : config_(config) {
  throwIfInvalid(config.validate(), "map configuration");
  model_ = config.logOddsModel();
  initialiseOpenVdb();
  impl_ = std::make_unique<detail::MapImpl>();
  impl_->log_odds = detail::LogOddsGrid::create(0.0f);
  impl_->log_odds->setTransform(detail::makeTransform(config.voxel_size_m));
  impl_->log_odds->setName("log_odds");
  impl_->log_odds->setGridClass(openvdb::GRID_UNKNOWN);
}

OccupancyMap::~OccupancyMap() = default;

VoxelIndex OccupancyMap::toIndex(const Eigen::Vector3d& p_world) const { return toVoxel(p_world, voxelSize()); }

Eigen::Vector3d OccupancyMap::toPoint(const VoxelIndex& ijk) const { return voxelCentre(ijk, voxelSize()); }

uint64_t OccupancyMap::version() const { return impl_->version.load(); }

void OccupancyMap::checkBatch(const PointBatch& batch) const {
  checkBatchButPoints(batch);
  checkPoints(batch);
}

void OccupancyMap::checkBatchButPoints(const PointBatch& batch) const {
  if (batch.empty()) throw Error("map: empty point batch (t = " + std::to_string(batch.t_s) + " s): nothing to integrate");
  const double limit_m = kMaxVoxelIndex * voxelSize();
  if (!batch.origin.allFinite() || (batch.origin.array().abs() >= limit_m).any()) {
    throw Error("map: batch origin " + formatPoint(batch.origin) + " must be finite and within " + std::to_string(limit_m) +
                " m of 0 (t = " + std::to_string(batch.t_s) + " s)");
  }
  if (batch.hasColor() && batch.colors.size() != batch.points.size()) {
    throw Error("map: batch has " + std::to_string(batch.colors.size()) + " colours for " +
                std::to_string(batch.points.size()) + " points (must be equal, or no colours)");
  }
}

void OccupancyMap::checkBatch(const PointBatch& batch, const Eigen::AlignedBox3f& points_box) const {
  if (points_box.isEmpty() || !points_box.min().allFinite() || !points_box.max().allFinite()) return checkBatch(batch);
  const float limit_f = static_cast<float>(kMaxVoxelIndex * voxelSize());
  if ((points_box.min().array().abs() >= limit_f).any() || (points_box.max().array().abs() >= limit_f).any()) {
    return checkBatch(batch);
  }
  checkBatchButPoints(batch);
}

void OccupancyMap::checkPoints(const PointBatch& batch) const {
  const double limit_m = kMaxVoxelIndex * voxelSize();
  const float limit_f = static_cast<float>(limit_m);
  // |x| < limit_f for every coordinate, in one vectorised pass without branches; the message's
  // loop below runs only for a bad batch. As integers, the bits of |x| less those of limit_f
  // (positive, finite) are negative exactly when |x| < limit_f (NaN and infinity have larger
  // bits), so the AND of all the differences is negative when every coordinate is good. Over
  // the points as one array of floats: a bool &= per point and axis did not vectorise.
  const uint32_t limit_bits = std::bit_cast<uint32_t>(limit_f);
  const float* xyz = batch.points.front().data();
  uint32_t all_below = ~0u;
  for (size_t i = 0; i < 3 * batch.points.size(); ++i) {
    all_below &= (std::bit_cast<uint32_t>(xyz[i]) & 0x7fffffffu) - limit_bits;
  }
  if ((all_below >> 31) != 0) return;
  for (size_t i = 0; i < batch.points.size(); ++i) {
    const Eigen::Vector3f& p = batch.points[i];
    if (!p.allFinite() || (p.array().abs() >= limit_f).any()) {
      throw Error("map: point " + std::to_string(i) + " of the batch is " + formatPoint(p.cast<double>()) +
                  ": must be finite and within " + std::to_string(limit_m) + " m of 0 (t = " + std::to_string(batch.t_s) +
                  " s)");
    }
  }
}

MapDelta OccupancyMap::integrate(const PointBatch& batch) {
  checkBatch(batch);
  std::lock_guard<std::mutex> writer(impl_->writer_mutex);
  RayBatch& rays = impl_->scratch;
  rays.build(batch, voxelSize(), config_.max_range_m, config_.num_threads, config_.ray_stop_run);
  return publish(rays.updates(), rays.numRays());
}

MapDelta OccupancyMap::integrate(const PointBatch& batch, RayBatch& rays) {
  checkBatch(batch);
  std::lock_guard<std::mutex> writer(impl_->writer_mutex);
  rays.build(batch, voxelSize(), config_.max_range_m, config_.num_threads, config_.ray_stop_run);
  return publish(rays.updates(), rays.numRays());
}

MapDelta OccupancyMap::replaceBlocks(std::span<const BlockState> blocks) {
  std::vector<uint64_t> keys;
  keys.reserve(blocks.size());
  for (const BlockState& state : blocks) {
    const VoxelIndex base = state.block * kBlockSide;
    if (!inMapRange(base) || !inMapRange(base + VoxelIndex::Constant(kBlockSide - 1))) {
      throw Error("map: replaced block (" + std::to_string(state.block.x()) + ", " + std::to_string(state.block.y()) +
                  ", " + std::to_string(state.block.z()) + ") lies outside the map's range");
    }
    keys.push_back(detail::packIndex(state.block));
  }
  std::sort(keys.begin(), keys.end());
  if (std::adjacent_find(keys.begin(), keys.end()) != keys.end()) throw Error("map: a block is replaced twice");
  std::lock_guard<std::mutex> writer(impl_->writer_mutex);
  MapDelta delta;
  const double s = voxelSize();
  auto& tree = impl_->log_odds->tree();
  openvdb::tree::ValueAccessor<detail::LogOddsTree, false> acc(tree);
  const size_t group = static_cast<size_t>(config_.publish_blocks);
  std::vector<std::pair<int, int32_t>> packed;
  for (size_t begin = 0; begin < blocks.size(); begin += group) {
    const size_t end = std::min(blocks.size(), begin + group);
    std::unique_lock<detail::FairSharedMutex> lock(impl_->grid_mutex);
    for (size_t b = begin; b < end; ++b) {
      const BlockState& state = blocks[b];
      const Coord origin = coordOf(state.block * kBlockSide);
      auto* leaf = acc.probeLeaf(origin);
      uint64_t any_new = 0;
      for (uint64_t word : state.view.known) any_new |= word;
      std::array<uint64_t, 8> changed{};
      if (leaf != nullptr || any_new != 0) {
        if (leaf == nullptr) {
          leaf = acc.touchLeaf(origin);
          impl_->indexLeaf(*leaf);
        }
        float* values = leaf->buffer().data();
        auto& known_mask = leaf->getValueMask();
        for (int w = 0; w < 8; ++w) {
          uint64_t& known = known_mask.template getWord<uint64_t>(w);
          const uint64_t next = state.view.known[w];
          uint64_t differs = known ^ next;
          for (uint64_t rest = next; rest != 0; rest &= rest - 1) {
            const int i = w * 64 + __builtin_ctzll(rest);
            if (values[i] != state.view.log_odds[i]) differs |= 1ull << (i & 63);
            values[i] = state.view.log_odds[i];
          }
          for (uint64_t rest = known & ~next; rest != 0; rest &= rest - 1) values[w * 64 + __builtin_ctzll(rest)] = 0.0f;
          known = next;
          changed[w] = differs;
        }
      }
      packed.clear();
      for (const VoxelColor& c : state.colors) packed.emplace_back(c.offset, detail::packColor(c.rgb, c.count));
      const auto old_colors = impl_->color.blockColors(state.block);
      if (old_colors != packed) {
        impl_->color.replaceBlock(state.block, packed);
        for (const auto& [offset, value] : old_colors) changed[offset >> 6] |= 1ull << (offset & 63);
        for (const auto& [offset, value] : packed) changed[offset >> 6] |= 1ull << (offset & 63);
      }
      const VoxelBox box = boxOfBits(state.block, changed);
      if (!box.isEmpty()) noteChanged(delta, state.block, box, s);
    }
  }
  finishDelta(delta, s);
  impl_->version.fetch_add(1);
  return delta;
}

void OccupancyMap::checkDepthFrame(const DepthFrame& f) const {
  const std::string where = "map: depth frame (t = " + std::to_string(f.t_s) + " s)";
  if (f.width < 1 || f.height < 1) {
    throw Error(where + " is " + std::to_string(f.width) + "x" + std::to_string(f.height) + ": must be at least 1x1");
  }
  const size_t pixels = static_cast<size_t>(f.width) * static_cast<size_t>(f.height);
  if (f.depth_m.size() != pixels) {
    throw Error(where + " has " + std::to_string(f.depth_m.size()) + " depths for " + std::to_string(pixels) + " pixels");
  }
  if (f.hasColor() && f.colors.size() != pixels) {
    throw Error(where + " has " + std::to_string(f.colors.size()) + " colours for " + std::to_string(pixels) +
                " pixels (must be equal, or no colours)");
  }
  if (!(f.fx > 0.0) || !(f.fy > 0.0) || !std::isfinite(f.fx) || !std::isfinite(f.fy) || !std::isfinite(f.cx) ||
      !std::isfinite(f.cy)) {
    throw Error(where + ": intrinsics fx " + std::to_string(f.fx) + ", fy " + std::to_string(f.fy) + ", cx " +
                std::to_string(f.cx) + ", cy " + std::to_string(f.cy) + " must be finite with fx, fy > 0");
  }
  if (!f.T_world_cam.matrix().allFinite()) throw Error(where + ": camera pose T_world_cam must be finite");
  // The farthest point: the largest depth at the image's corners (rays spread most there).
  double max_depth = 0.0;
  for (float d : f.depth_m) {
    if (d > 0.0f && std::isfinite(d)) max_depth = std::max(max_depth, static_cast<double>(d));
  }
  const double corner = std::hypot(std::max(std::fabs(-0.5 - f.cx), std::fabs(f.width - 0.5 - f.cx)) / f.fx,
                                   std::max(std::fabs(-0.5 - f.cy), std::fabs(f.height - 0.5 - f.cy)) / f.fy, 1.0);
  const double limit_m = kMaxVoxelIndex * voxelSize();
  const double reach_m = f.T_world_cam.translation().cwiseAbs().maxCoeff() + max_depth * corner;
  if (!(reach_m < limit_m)) {
    throw Error(where + ": camera and points must lie within " + std::to_string(limit_m) + " m of 0 (they reach " +
                std::to_string(reach_m) + " m)");
  }
}

MapDelta OccupancyMap::integrateDepth(const DepthFrame& frame) {
  checkDepthFrame(frame);
  std::lock_guard<std::mutex> writer(impl_->writer_mutex);
  ProjectiveBatch& batch = impl_->projective_scratch;
  batch.build(frame, voxelSize(), config_.max_range_m, config_.num_threads);
  return publish(batch.updates(), batch.numRays());
}

MapDelta OccupancyMap::publish(const BatchUpdates& updates, size_t points_used) {
  MapDelta delta;
  delta.points_used = points_used;
  delta.voxels_updated = updates.numUpdated();
  const double s = voxelSize();
  auto& tree = impl_->log_odds->tree();
  openvdb::tree::ValueAccessor<detail::LogOddsTree, false> acc(tree);
  const size_t group = static_cast<size_t>(config_.publish_blocks);
  for (size_t begin = 0; begin < updates.numBlocks(); begin += group) {
    const size_t end = std::min(updates.numBlocks(), begin + group);
    std::unique_lock<detail::FairSharedMutex> lock(impl_->grid_mutex);
    for (size_t b = begin; b < end; ++b) {
      const BlockIndex& block = updates.block(b);
      const BlockMasks& masks = updates.masks(b);
      const Coord origin = coordOf(block * kBlockSide);
      auto* leaf = acc.probeLeaf(origin);
      if (leaf == nullptr) {  // a new leaf: existing ones are indexed already and never move
        leaf = acc.touchLeaf(origin);
        impl_->indexLeaf(*leaf);
      }
      // Straight on the leaf's buffer and value mask (one 64-bit word = 64 voxels of one x slice).
      float* values = leaf->buffer().data();
      auto& known_mask = leaf->getValueMask();
      std::array<uint64_t, 8> changed{};
      for (int w = 0; w < 8; ++w) {
        uint64_t& known = known_mask.template getWord<uint64_t>(w);
        const uint64_t hits = masks.hit[w];
        const uint64_t update = masks.free[w] | hits;
        changed[w] = detail::publishWord(values + w * 64, known, update, hits, model_);
        known |= changed[w];
      }
      const VoxelBox box = boxOfBits(block, changed);
      if (!box.isEmpty()) noteChanged(delta, block, box, s);
    }
  }
  // Colours of the hit voxels: a running mean per voxel.
  if (!updates.colors().empty()) {
    detail::ColorStore& colors = impl_->color;
    const size_t n = updates.colors().size();
    // 8 colours per block of a group: a colour costs about a tenth of a block's publishing (a
    // hash probe), so a colour group holds the lock about as long as a block group.
    for (size_t begin = 0; begin < n; begin += group * 8) {
      const size_t end = std::min(n, begin + group * 8);
      std::unique_lock<detail::FairSharedMutex> lock(impl_->grid_mutex);
      for (size_t i = begin; i < end; ++i) {
        const EndpointColor& c = updates.colors()[i];
        bool inserted;
        int32_t& packed = colors.at(c.ijk, inserted);
        if (inserted) {
          packed = detail::packColor(c.rgb, 1);
          continue;
        }
        const int count = detail::colorCount(packed);
        const auto old = detail::unpackColor(packed);
        std::array<uint8_t, 3> mean;
        for (int k = 0; k < 3; ++k) {
          mean[k] = static_cast<uint8_t>((old[k] * count + c.rgb[k] + (count + 1) / 2) / (count + 1));
        }
        packed = detail::packColor(mean, std::min(count + 1, 127));
      }
    }
  }
  finishDelta(delta, s);
  impl_->version.fetch_add(1);
  return delta;
}

template <typename Predicate>
MapDelta OccupancyMap::removeVoxels(const VoxelBox& candidates, bool everywhere, Predicate&& remove) {
  std::lock_guard<std::mutex> writer(impl_->writer_mutex);
  std::unique_lock<detail::FairSharedMutex> lock(impl_->grid_mutex);
  MapDelta delta;
  const double s = voxelSize();
  const openvdb::CoordBBox region(coordOf(candidates.min), coordOf(candidates.max));
  auto removed = [&](const VoxelIndex& ijk) {
    return (everywhere || candidates.contains(ijk)) && remove(voxelCentre(ijk, s));
  };
  auto& tree = impl_->log_odds->tree();
  // Leaves left without a known voxel (also any a loaded file brought) are the ones pruneInactive
  // deletes: only they leave the leaf index; the other leaves stay where they are.
  std::vector<BlockIndex> emptied;
  for (auto leaf = tree.beginLeaf(); leaf; ++leaf) {
    const Coord origin = leaf->origin();
    const BlockIndex block(origin.x() >> kBlockShift, origin.y() >> kBlockShift, origin.z() >> kBlockShift);
    if (everywhere || region.hasOverlap(leaf->getNodeBoundingBox())) {
      VoxelBox box;
      for (auto it = leaf->beginValueOn(); it; ++it) {
        const Coord xyz = it.getCoord();
        const VoxelIndex ijk(xyz.x(), xyz.y(), xyz.z());
        if (!removed(ijk)) continue;
        it.setValueOff();
        it.setValue(0);
        box.extend(ijk);
      }
      if (!box.isEmpty()) noteChanged(delta, block, box, s);
    }
    if (leaf->isEmpty()) emptied.push_back(block);
  }
  // tools::pruneInactive, serially (its node list is built with TBB even when not threaded): a
  // clear touches few nodes, and TBB's (uninstrumented) workers make ThreadSanitizer report races.
  openvdb::tree::NodeManager<detail::LogOddsTree, detail::LogOddsTree::DEPTH - 2> nodes(tree, /*serial=*/true);
  openvdb::tools::InactivePruneOp<detail::LogOddsTree> prune(tree);
  nodes.foreachBottomUp(prune, /*threaded=*/false);
  for (const BlockIndex& block : emptied) impl_->leaf_index.erase(block);
  impl_->leaf_index.shrinkToFit();
  if (everywhere) {
    // A crop or reset also drops the integration scratch, whose capacity the largest batch so far
    // set (hundreds of MB after batches of rays in all directions); the next batch allocates anew.
    impl_->scratch = RayBatch();
    impl_->projective_scratch = ProjectiveBatch();
  }
  const VoxelBox candidate_blocks{blockOf(candidates.min), blockOf(candidates.max)};
  impl_->color.eraseIf([&](const BlockIndex& block) { return everywhere || candidate_blocks.contains(block); }, removed);
  finishDelta(delta, s);
  impl_->version.fetch_add(1);
  return delta;
}

MapDelta OccupancyMap::clearBox(const Aabb& box_m) {
  if (!box_m.min_m.allFinite() || !box_m.max_m.allFinite() || box_m.isEmpty()) {
    throw Error("map: clear box " + formatPoint(box_m.min_m) + " - " + formatPoint(box_m.max_m) +
                " must be finite with min <= max");
  }
  // Clipped to the map's range (map_range.h): a box reaching beyond it clears what lies within.
  const VoxelBox candidates = voxelsOfBox(box_m, voxelSize(), "map: clear box").voxels;
  return removeVoxels(candidates, false, [&](const Eigen::Vector3d& c) { return box_m.contains(c); });
}

MapDelta OccupancyMap::clearSphere(const Eigen::Vector3d& centre_m, double radius_m) {
  if (!centre_m.allFinite() || !(radius_m >= 0.0) || !std::isfinite(radius_m)) {
    throw Error("map: clear sphere at " + formatPoint(centre_m) + " radius " + std::to_string(radius_m) +
                " m: centre must be finite and radius finite and >= 0");
  }
  const Aabb bounds{(centre_m.array() - radius_m).matrix(), (centre_m.array() + radius_m).matrix()};
  const VoxelBox candidates = voxelsOfBox(bounds, voxelSize(), "map: clear sphere").voxels;
  const double r2 = radius_m * radius_m;
  return removeVoxels(candidates, false, [&](const Eigen::Vector3d& c) { return (c - centre_m).squaredNorm() <= r2; });
}

MapDelta OccupancyMap::cropToRadius(const Eigen::Vector3d& centre_m, double radius_m) {
  if (!centre_m.allFinite() || !(radius_m >= 0.0) || !std::isfinite(radius_m)) {
    throw Error("map: crop at " + formatPoint(centre_m) + " radius " + std::to_string(radius_m) +
                " m: centre must be finite and radius finite and >= 0");
  }
  const double r2 = radius_m * radius_m;
  return removeVoxels(VoxelBox{}, true, [&](const Eigen::Vector3d& c) { return (c - centre_m).squaredNorm() > r2; });
}

MapDelta OccupancyMap::reset() {
  return removeVoxels(VoxelBox{}, true, [](const Eigen::Vector3d&) { return true; });
}

MapStats OccupancyMap::stats() const {
  std::shared_lock<detail::FairSharedMutex> lock(impl_->grid_mutex);
  MapStats out;
  out.voxel_size_m = voxelSize();
  const auto& tree = impl_->log_odds->constTree();
  for (auto it = tree.cbeginValueOn(); it; ++it) {
    // Tiles never occur (integration writes voxels), but count them right if a loaded file has them.
    const uint64_t count = it.getVoxelCount();
    if (model_.isOccupied(*it)) {
      out.occupied += count;
    } else {
      out.free += count;
    }
    openvdb::CoordBBox bbox;
    it.getBoundingBox(bbox);
    out.bounds.extend(VoxelIndex(bbox.min().x(), bbox.min().y(), bbox.min().z()));
    out.bounds.extend(VoxelIndex(bbox.max().x(), bbox.max().y(), bbox.max().z()));
  }
  if (!out.bounds.isEmpty()) {
    const Eigen::Vector3d extent = (out.bounds.max - out.bounds.min).cast<double>().array() + 1.0;
    out.unknown_in_bounds = static_cast<uint64_t>(extent.prod()) - out.occupied - out.free;
    out.bounds_m.min_m = out.bounds.min.cast<double>() * voxelSize();
    out.bounds_m.max_m = (out.bounds.max.cast<double>().array() + 1.0).matrix() * voxelSize();
  }
  // Serial count: Grid::memUsage() runs a TBB reduction, whose (uninstrumented) worker threads
  // ThreadSanitizer reports as races; stats() is not a hot path.
  out.memory_bytes = openvdb::tools::memUsage(impl_->log_odds->constTree(), false) + impl_->color.memoryBytes() +
                     impl_->leaf_index.memoryBytes();
  return out;
}

OccupancyMap::ConstAccessor::ConstAccessor(const OccupancyMap& map)
    : map_(&map), lock_(map.impl_->grid_mutex), impl_(std::make_unique<detail::AccessorImpl>(*map.impl_)) {}

OccupancyMap::ConstAccessor::~ConstAccessor() = default;
OccupancyMap::ConstAccessor::ConstAccessor(ConstAccessor&&) noexcept = default;

bool OccupancyMap::ConstAccessor::logOdds(const VoxelIndex& ijk, float& l) const { return impl_->logOdds(ijk, l); }

VoxelState OccupancyMap::ConstAccessor::state(const VoxelIndex& ijk) const {
  float l;
  if (!impl_->logOdds(ijk, l)) return VoxelState::kUnknown;
  return map_->model_.isOccupied(l) ? VoxelState::kOccupied : VoxelState::kFree;
}

void OccupancyMap::ConstAccessor::logOdds(std::span<const VoxelIndex> ijk, std::span<float> l,
                                          std::span<uint8_t> known) const {
  // Groups of kGroup voxels in three passes: prefetch their table slots, then find their leaves
  // and prefetch mask word and value, then read. Each pass issues kGroup independent loads whose
  // cache misses overlap, where one lookup after another waits for each miss in turn.
  constexpr size_t kGroup = 16;
  const LeafIndex& index = *impl_->leaves;
  const LeafRef* leaves[kGroup];
  for (size_t begin = 0; begin < ijk.size(); begin += kGroup) {
    const size_t n = std::min(kGroup, ijk.size() - begin);
    for (size_t g = 0; g < n; ++g) index.prefetch(blockOf(ijk[begin + g]));
    for (size_t g = 0; g < n; ++g) {
      leaves[g] = index.find(blockOf(ijk[begin + g]));
      if (leaves[g] != nullptr) leaves[g]->prefetch(offsetInBlock(ijk[begin + g]));
    }
    for (size_t g = 0; g < n; ++g) {
      const size_t i = begin + g;
      known[i] = leaves[g] != nullptr && leaves[g]->logOdds(offsetInBlock(ijk[i]), l[i]);
    }
  }
}

void OccupancyMap::ConstAccessor::states(std::span<const VoxelIndex> ijk, std::span<VoxelState> out) const {
  constexpr size_t kChunk = 256;
  float l[kChunk];
  uint8_t known[kChunk];
  for (size_t begin = 0; begin < ijk.size(); begin += kChunk) {
    const size_t n = std::min(kChunk, ijk.size() - begin);
    logOdds(ijk.subspan(begin, n), std::span<float>(l, n), std::span<uint8_t>(known, n));
    for (size_t i = 0; i < n; ++i) {
      out[begin + i] = !known[i] ? VoxelState::kUnknown
                                 : (map_->model_.isOccupied(l[i]) ? VoxelState::kOccupied : VoxelState::kFree);
    }
  }
}

double OccupancyMap::ConstAccessor::probability(const VoxelIndex& ijk) const {
  float l;
  if (!logOdds(ijk, l)) return 0.5;
  return mapping::probability(l);
}

bool OccupancyMap::ConstAccessor::color(const VoxelIndex& ijk, std::array<uint8_t, 3>& rgb) const {
  int32_t packed;
  if (!impl_->color->get(ijk, packed)) return false;
  rgb = detail::unpackColor(packed);
  return true;
}

std::vector<BlockIndex> OccupancyMap::ConstAccessor::knownBlocks() const {
  const auto& tree = map_->impl_->log_odds->constTree();
  std::vector<uint64_t> keys;
  keys.reserve(tree.leafCount());
  for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
    if (leaf->isEmpty()) continue;
    const Coord o = leaf->origin();
    keys.push_back(floatTreeOrderKey(BlockIndex(o.x() >> kBlockShift, o.y() >> kBlockShift, o.z() >> kBlockShift)));
  }
  std::sort(keys.begin(), keys.end());
  std::vector<BlockIndex> blocks(keys.size());
  std::transform(keys.begin(), keys.end(), blocks.begin(), blockOfFloatTreeOrderKey);
  return blocks;
}

bool OccupancyMap::ConstAccessor::readBlock(const BlockIndex& block, BlockView& view) const {
  // The live tree holds no tiles (integration writes voxels, loading splits a file's tiles).
  const LeafRef* leaf = impl_->leaves->find(block);
  if (leaf == nullptr) {
    view.known.fill(0);
    return false;
  }
  uint64_t any = 0;
  for (int w = 0; w < 8; ++w) {
    view.known[w] = leaf->known[w];
    any |= leaf->known[w];
  }
  std::copy(leaf->values, leaf->values + kBlockVoxels, view.log_odds.begin());
  return any != 0;
}

std::vector<VoxelColor> OccupancyMap::ConstAccessor::blockColors(const BlockIndex& block) const {
  std::vector<VoxelColor> out;
  for (const auto& [offset, packed] : impl_->color->blockColors(block)) {
    out.push_back(VoxelColor{static_cast<uint16_t>(offset), detail::unpackColor(packed),
                             static_cast<uint8_t>(detail::colorCount(packed))});
  }
  return out;
}

bool OccupancyMap::ConstAccessor::readBlockMasks(const BlockIndex& block, std::array<uint64_t, 8>& known,
                                                 std::array<uint64_t, 8>& occupied) const {
  known.fill(0);
  occupied.fill(0);
  const LeafRef* leaf = impl_->leaves->find(block);
  if (leaf == nullptr) return false;
  const float* values = leaf->values;
  const float threshold = map_->model_.occupied;
  bool any = false;
  for (int w = 0; w < 8; ++w) {
    known[w] = leaf->known[w];
    any |= known[w] != 0;
    if (known[w] == 0) continue;
    // LogOddsModel::isOccupied on the known voxels, 4 per SSE2 compare (occupied_mask.h).
    occupied[w] = detail::occupiedMask(values + w * 64, known[w], threshold);
  }
  return any;
}

}  // namespace cenote::mapping
