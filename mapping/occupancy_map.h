// occupancy_map.h: probabilistic occupancy of the world, log-odds on a sparse voxel grid (OpenVDB),
// with a colour per occupied voxel.
// Units: metres (voxel_size_m fixed at construction). Frame: world. Grid convention: voxel_types.h.
// Unknown is never free: a voxel never observed (or cleared) reports VoxelState::kUnknown.
//
// Threads: one writer at a time (integrate / clear / crop / reset / load serialise on a writer
// mutex), any number of readers, each with its own ConstAccessor, at the same time. No data race:
//  - integrate() first computes the whole batch's updates into private scratch (RayBatch) without
//    any lock on the grid; this is most of the work.
//  - It then publishes them block by block, taking the grid's exclusive lock for at most
//    MapConfig::publish_blocks blocks at a time (64 blocks: about 0.1 ms; 256 held it for 0.3-0.5
//    ms, and the colours of a frame for up to 1.5 ms, on the bench machine), then its colours as
//    many at a time (8 per block of a group). Between two such groups readers get in, so a query
//    never waits for a whole frame's integration.
//  - A ConstAccessor holds the grid's shared lock for its lifetime.
// Chosen over copy-on-write snapshots of the tree because it costs no copy per frame, keeps memory
// at one map, and makes readers wait for at most one short group; the price is that a reader can
// see a frame half-published (each block is consistent, the frame as a whole is not).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <shared_mutex>
#include <span>
#include <vector>

#include "common/point_batch.h"
#include "mapping/detail/fair_shared_mutex.h"
#include "mapping/log_odds.h"
#include "mapping/map_config.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping {

struct DepthFrame;   // integration/depth_frame.h
class BatchUpdates;  // integration/batch_updates.h
class RayBatch;      // integration/ray_batch.h

namespace detail {
struct MapImpl;
struct AccessorImpl;
class MapAccess;
}  // namespace detail

// The 512 voxels of one block, copied out of the map (read with ConstAccessor::readBlock).
struct BlockView {
  std::array<uint64_t, 8> known{};             // bit offsetInBlock(ijk): observed
  std::array<float, kBlockVoxels> log_odds{};  // meaningful where known
};

// The colour of one voxel of a block: its offsetInBlock, mean RGB and the number of batches averaged
// (saturating at 127, as the map keeps it).
struct VoxelColor {
  uint16_t offset = 0;
  std::array<uint8_t, 3> rgb{};
  uint8_t count = 0;
};

// A block's whole state, as replaceBlocks() writes it (history/map_history.h re-builds blocks).
struct BlockState {
  BlockIndex block = BlockIndex::Zero();
  BlockView view;                  // known bits and log-odds (values where unknown are ignored)
  std::vector<VoxelColor> colors;  // ascending offset, on known voxels only
};

struct MapStats {
  double voxel_size_m = 0.0;
  uint64_t occupied = 0;
  uint64_t free = 0;
  uint64_t unknown_in_bounds = 0;  // never-observed voxels inside the bounding box of known ones
  VoxelBox bounds;                 // of the known voxels
  Aabb bounds_m;
  uint64_t memory_bytes = 0;  // of the log-odds grid (OpenVDB memUsage) and the colours
};

class OccupancyMap {
 public:
  // @throws Error listing every failed rule of the config.
  explicit OccupancyMap(const MapConfig& config);
  ~OccupancyMap();
  OccupancyMap(const OccupancyMap&) = delete;
  OccupancyMap& operator=(const OccupancyMap&) = delete;

  const MapConfig& config() const { return config_; }
  const LogOddsModel& model() const { return model_; }
  double voxelSize() const { return config_.voxel_size_m; }
  VoxelIndex toIndex(const Eigen::Vector3d& p_world) const;
  Eigen::Vector3d toPoint(const VoxelIndex& ijk) const;  // voxel centre

  // Casts a ray from batch.origin to every point: free space along it, a hit at its end; see
  // integration/ray_batch.h for the exact rules (dedup per voxel, max range, occupied wins).
  // @return the changed blocks and their bounding box.
  // @throws Error, leaving the map unchanged, for: an empty batch, a non-finite origin or point,
  //   colours given for some points only, a point or origin farther than kMaxVoxelIndex voxels
  //   from 0 on an axis (voxel_types.h).
  MapDelta integrate(const PointBatch& batch);
  // The checks integrate() makes of a batch. @throws Error as integrate() does.
  void checkBatch(const PointBatch& batch) const;
  // The same, given the box of the batch's points (computed where they were made): the box is
  // checked instead of every point (each point only when the box fails, to name the bad one).
  void checkBatch(const PointBatch& batch, const Eigen::AlignedBox3f& points_box) const;
  // The same as integrate(batch), computing the updates in the caller's `rays`, which holds them afterwards (the frame
  // store records them: history/map_history.h).
  MapDelta integrate(const PointBatch& batch, RayBatch& rays);

  // Replaces whole blocks by the given states (a block with no known voxel becomes unknown), in
  // groups of publish_blocks per exclusive lock: a reader sees each block either as it was or as
  // given, never a mix. @return the blocks whose voxels or colours changed. Blocks must be unique
  // and within the map's range (voxel_types.h); @throws Error otherwise, leaving the map unchanged.
  MapDelta replaceBlocks(std::span<const BlockState> blocks);

  // Projective integration of a depth image with intrinsics and pose (integration/
  // projective_batch.h): every voxel of the frustum's blocks is projected into the image once; free
  // where its pixel sees past it, a hit at each pixel's back-projected point. Same rules (max range,
  // pixels without depth carve nothing, each voxel updated at most once, occupied wins), publishing
  // and MapDelta as integrate().
  // @throws Error, leaving the map unchanged, for: width or height < 1, depth (or colours, when
  //   given) not width * height, fx or fy not finite and > 0, cx or cy not finite, a non-finite
  //   pose, a camera or point farther than kMaxVoxelIndex voxels from 0 on an axis.
  MapDelta integrateDepth(const DepthFrame& frame);

  // Forget (make unknown) the voxels whose centre lies in the box / sphere, or outside the sphere.
  // A box or sphere reaching beyond the map's range (map_range.h) clears the part within it.
  // Blocks left without a known voxel are freed; cropToRadius and reset also free the integration
  // scratch (the next integrate allocates it again).
  // @throws Error for a non-finite or negative size. @return what changed.
  MapDelta clearBox(const Aabb& box_m);
  MapDelta clearSphere(const Eigen::Vector3d& centre_m, double radius_m);
  MapDelta cropToRadius(const Eigen::Vector3d& centre_m, double radius_m);
  MapDelta reset();

  MapStats stats() const;
  // Incremented by every change; lets a reader tell whether the map moved under it.
  uint64_t version() const;

  // Read access for one thread; holds the map's shared lock while it lives.
  // @warning hold it for one batch of queries, not across frames: writers wait while any accessor
  //   lives. Never share one between threads.
  class ConstAccessor {
   public:
    ~ConstAccessor();
    ConstAccessor(ConstAccessor&&) noexcept;
    ConstAccessor& operator=(ConstAccessor&&) = delete;

    // Log-odds of a voxel; false (and l untouched) when unknown.
    bool logOdds(const VoxelIndex& ijk, float& l) const;
    VoxelState state(const VoxelIndex& ijk) const;
    // The same answers as logOdds() / state() voxel by voxel (known[i] = 0 and l[i] untouched where
    // unknown), several times faster for scattered voxels: the lookups of a group are interleaved
    // with software prefetches, so their cache misses overlap. Spans of equal size.
    void logOdds(std::span<const VoxelIndex> ijk, std::span<float> l, std::span<uint8_t> known) const;
    void states(std::span<const VoxelIndex> ijk, std::span<VoxelState> out) const;
    // Occupancy probability; 0.5 for unknown (check state() first).
    double probability(const VoxelIndex& ijk) const;
    // Mean colour of the points that hit the voxel; false when it has none.
    bool color(const VoxelIndex& ijk, std::array<uint8_t, 3>& rgb) const;
    // Every block holding a known voxel, in the order a standard OpenVDB FloatTree visits its leaves.
    std::vector<BlockIndex> knownBlocks() const;
    // Copies one block; false (view all unknown) when the block holds no known voxel.
    bool readBlock(const BlockIndex& block, BlockView& view) const;
    // Known and occupied bits of one block (bit offsetInBlock(ijk)), without copying its values;
    // false (both all zero) when the block holds no known voxel.
    bool readBlockMasks(const BlockIndex& block, std::array<uint64_t, 8>& known, std::array<uint64_t, 8>& occupied) const;
    // The colours of one block's voxels, ascending offset (empty when none).
    std::vector<VoxelColor> blockColors(const BlockIndex& block) const;
    const OccupancyMap& map() const { return *map_; }

   private:
    friend class OccupancyMap;
    explicit ConstAccessor(const OccupancyMap& map);
    const OccupancyMap* map_;
    std::shared_lock<detail::FairSharedMutex> lock_;
    std::unique_ptr<detail::AccessorImpl> impl_;
  };
  ConstAccessor constAccessor() const { return ConstAccessor(*this); }

 private:
  friend class detail::MapAccess;
  void checkDepthFrame(const DepthFrame& frame) const;
  // checkBatch's two halves: everything but the points, and the points one by one.
  void checkBatchButPoints(const PointBatch& batch) const;
  void checkPoints(const PointBatch& batch) const;
  // Writes the updates of a computed batch (RayBatch or ProjectiveBatch, from points_used points)
  // into the grids, publish_blocks blocks per exclusive lock. Called with the writer mutex held.
  MapDelta publish(const BatchUpdates& updates, size_t points_used);
  template <typename Predicate>
  MapDelta removeVoxels(const VoxelBox& candidates, bool everywhere, Predicate&& remove);

  MapConfig config_;
  LogOddsModel model_;
  std::unique_ptr<detail::MapImpl> impl_;
};

}  // namespace cenote::mapping
