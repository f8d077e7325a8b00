#include "mapping/integration/ray_batch.h"

#include <omp.h>

#include <algorithm>
#include <numeric>

#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

// Marks voxels into one thread's block masks; caches the last block.
class MaskWriter {
 public:
  MaskWriter(detail::BlockTable& table, std::vector<BlockMasks>& masks) : table_(table), masks_(masks) {}

  BlockMasks& blockOf(const VoxelIndex& ijk) {
    const BlockIndex b = mapping::blockOf(ijk);
    if (current_ == nullptr || b != current_block_) {
      bool inserted;
      const uint32_t slot = table_.findOrInsert(detail::packIndex(b), inserted);
      if (inserted) masks_.emplace_back();
      current_ = &masks_[slot];
      current_block_ = b;
    }
    return *current_;
  }
  void setFree(const VoxelIndex& ijk) {
    const int o = offsetInBlock(ijk);
    blockOf(ijk).free[o >> 6] |= 1ull << (o & 63);
  }
  // Marks ijk free; false when it already was.
  bool setFreeIfNew(const VoxelIndex& ijk) {
    const int o = offsetInBlock(ijk);
    uint64_t& word = blockOf(ijk).free[o >> 6];
    const uint64_t bit = 1ull << (o & 63);
    if (word & bit) return false;
    word |= bit;
    return true;
  }
  void setHit(const VoxelIndex& ijk) {
    const int o = offsetInBlock(ijk);
    blockOf(ijk).hit[o >> 6] |= 1ull << (o & 63);
    current_ = nullptr;  // masks_ may grow on the next insertion; the reference above is done
  }

 private:
  detail::BlockTable& table_;
  std::vector<BlockMasks>& masks_;
  BlockMasks* current_ = nullptr;
  BlockIndex current_block_;
};

}  // namespace

void RayBatch::build(const PointBatch& batch, double voxel_size_m, double max_range_m, int num_threads, int stop_run) {
  const bool exact = stop_run <= 0;
  // 1. Unique endpoint voxels, with colour sums.
  endpoint_table_.clear();
  endpoints_.clear();
  color_sums_.clear();
  const bool colored = batch.hasColor();
  for (size_t i = 0; i < batch.points.size(); ++i) {
    const VoxelIndex ijk = toVoxel(batch.points[i].cast<double>(), voxel_size_m);
    bool inserted;
    const uint32_t slot = endpoint_table_.findOrInsert(detail::packIndex(ijk), inserted);
    if (inserted) {
      endpoints_.push_back(ijk);
      if (colored) color_sums_.push_back({0, 0, 0, 0});
    }
    if (colored) {
      auto& sum = color_sums_[slot];
      sum[0] += batch.colors[i][0];
      sum[1] += batch.colors[i][1];
      sum[2] += batch.colors[i][2];
      sum[3] += 1;
    }
  }
  num_rays_ = endpoints_.size();

  // 2. March the rays: a fixed number of chunks of consecutive endpoints (image bands), each into
  // its own masks, so that the result does not depend on the thread count.
  const int threads = std::max(1, num_threads > 0 ? num_threads : omp_get_max_threads());
  const int chunks = exact ? threads : kRayChunks;
  if (markers_.size() < static_cast<size_t>(chunks)) markers_.resize(chunks);
  for (int t = 0; t < chunks; ++t) {
    markers_[t].table.clear();
    markers_[t].masks.clear();
  }
  const Eigen::Vector3d origin = batch.origin;
  const bool limited = max_range_m > 0.0;
  const long n = static_cast<long>(endpoints_.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int chunk = 0; chunk < chunks; ++chunk) {
    Marker& marker = markers_[chunk];
    MaskWriter writer(marker.table, marker.masks);
    const long begin = n * chunk / chunks, end_i = n * (chunk + 1) / chunks;
    for (long i = begin; i < end_i; ++i) {
      const Eigen::Vector3d end = voxelCentre(endpoints_[i], voxel_size_m);
      const Eigen::Vector3d ray = end - origin;
      const double range = ray.norm();
      const bool in_range = !limited || range <= max_range_m;
      const Eigen::Vector3d stop = in_range ? end : Eigen::Vector3d(origin + ray * (max_range_m / range));
      if (exact) {
        walkVoxels(origin, stop, voxel_size_m, false, [&](const VoxelIndex& ijk) {
          writer.setFree(ijk);
          return true;
        });
      } else {
        // From the end back to the origin, until stop_run voxels in a row were already carved by
        // earlier rays of the chunk: from there on they have carved (nearly) the same path.
        const VoxelIndex end_voxel = toVoxel(stop, voxel_size_m);
        int run = 0;
        walkVoxels(stop, origin, voxel_size_m, true, [&](const VoxelIndex& ijk) {
          if (ijk == end_voxel) return true;
          run = writer.setFreeIfNew(ijk) ? 0 : run + 1;
          return run < stop_run;
        });
      }
      if (in_range) writer.setHit(endpoints_[i]);
    }
  }

  // 3. Union of the chunks' masks into chunk 0's table.
  Marker& first = markers_[0];
  for (int t = 1; t < chunks; ++t) {
    Marker& other = markers_[t];
    for (uint32_t s = 0; s < other.table.size(); ++s) {
      bool inserted;
      const uint32_t slot = first.table.findOrInsert(other.table.keyOf(s), inserted);
      if (inserted) first.masks.emplace_back();
      for (int w = 0; w < 8; ++w) {
        first.masks[slot].free[w] |= other.masks[s].free[w];
        first.masks[slot].hit[w] |= other.masks[s].hit[w];
      }
    }
  }
  masks_.swap(first.masks);
  first.masks.clear();
  for (BlockMasks& m : masks_) {
    for (int w = 0; w < 8; ++w) m.free[w] &= ~m.hit[w];
  }
  order_.resize(masks_.size());
  std::iota(order_.begin(), order_.end(), 0u);
  std::sort(order_.begin(), order_.end(),
            [&](uint32_t a, uint32_t b) { return first.table.keyOf(a) < first.table.keyOf(b); });
  blocks_.resize(order_.size());
  for (size_t i = 0; i < order_.size(); ++i) blocks_[i] = detail::unpackIndex(first.table.keyOf(order_[i]));

  // 4. Mean colours of the hit voxels.
  colors_.clear();
  if (colored) {
    for (size_t i = 0; i < endpoints_.size(); ++i) {
      const auto& sum = color_sums_[i];
      const Eigen::Vector3d end = voxelCentre(endpoints_[i], voxel_size_m);
      if (limited && (end - origin).norm() > max_range_m) continue;
      const uint32_t c = sum[3];
      colors_.push_back({endpoints_[i],
                         {static_cast<uint8_t>((sum[0] + c / 2) / c), static_cast<uint8_t>((sum[1] + c / 2) / c),
                          static_cast<uint8_t>((sum[2] + c / 2) / c)}});
    }
  }
}

}  // namespace cenote::mapping
