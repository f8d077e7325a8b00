#include "server/viewer/block_sync.h"

#include <algorithm>
#include <bit>

namespace cenote::server::viewer {
namespace {

constexpr uint64_t kMask21 = (uint64_t{1} << 21) - 1;
constexpr size_t kDeletionBytes = 80;

struct Planned {
  uint64_t key;
  double distance2;
  uint64_t voxels;
  bool full;
};

uint64_t countOccupied(const std::array<uint64_t, 8>& occupied) {
  uint64_t n = 0;
  for (const uint64_t w : occupied) n += static_cast<uint64_t>(std::popcount(w));
  return n;
}

}  // namespace

uint64_t BlockSync::key(const mapping::BlockIndex& b) {
  return ((static_cast<uint64_t>(b.x()) & kMask21) << 42) | ((static_cast<uint64_t>(b.y()) & kMask21) << 21) |
         (static_cast<uint64_t>(b.z()) & kMask21);
}

mapping::BlockIndex BlockSync::unkey(uint64_t k) {
  auto axis = [](uint64_t v) {
    const int64_t x = static_cast<int64_t>(v & kMask21);
    return static_cast<int>(x >= (int64_t{1} << 20) ? x - (int64_t{1} << 21) : x);
  };
  return {axis(k >> 42), axis(k >> 21), axis(k)};
}

void BlockSync::setLevel(uint64_t k, Lod lod, const std::array<uint64_t, 8>& occupied, uint64_t time_ns) {
  auto [it, inserted] = sent_.try_emplace(k);
  if (!inserted && it->second.lod == Lod::kCoarse) --coarse_;
  it->second = {lod, occupied, time_ns};
  if (lod == Lod::kCoarse) ++coarse_;
  stale_.erase(k);
}

void BlockSync::forget(uint64_t k) {
  const auto it = sent_.find(k);
  if (it == sent_.end()) return;
  if (it->second.lod == Lod::kCoarse) --coarse_;
  sent_.erase(it);
  stale_.erase(k);
}

void BlockSync::markAll(const std::vector<mapping::BlockIndex>& known_blocks) {
  for (const auto& [k, sent] : sent_) dirty_.insert(k);
  for (const auto& b : known_blocks) dirty_.insert(key(b));
}

void BlockSync::markChanged(const std::vector<mapping::BlockIndex>& blocks) {
  for (const auto& b : blocks) dirty_.insert(key(b));
}

SyncStep BlockSync::next(const mapping::OccupancyMap::ConstAccessor& access, const Eigen::Vector3d& camera_m,
                         double budget_bytes, uint64_t time_ns) {
  const mapping::OccupancyMap& map = access.map();
  const double block_m = map.voxelSize() * mapping::kBlockSide;
  auto distance2 = [&](uint64_t k) {
    const Eigen::Vector3d centre = (unkey(k).cast<double>().array() + 0.5).matrix() * block_m;
    return (centre - camera_m).squaredNorm();
  };
  auto byDistance = [&](std::vector<std::pair<double, uint64_t>>& list) {
    std::sort(list.begin(), list.end());  // distance, then key: the same order for the same map
  };

  SyncStep step;
  SceneUpdateWriter writer(time_ns, frame_id_);
  double spent = 0.0;
  std::array<uint64_t, 8> known, occupied;
  std::vector<Planned> planned;

  // Dirty blocks, nearest first: deletions, and a coarse cube for each the budget reaches.
  std::vector<std::pair<double, uint64_t>> dirty;
  dirty.reserve(dirty_.size());
  for (const uint64_t k : dirty_) dirty.emplace_back(distance2(k), k);
  byDistance(dirty);
  size_t reached = 0;
  std::vector<uint64_t> held;  // sent less than resend_s ago: they stay dirty
  for (; reached < dirty.size(); ++reached) {
    const uint64_t k = dirty[reached].second;
    if (resend_ns_ > 0) {
      const auto recent = sent_.find(k);
      if (recent != sent_.end() && time_ns < recent->second.time_ns + resend_ns_) {
        held.push_back(k);
        continue;
      }
    }
    access.readBlockMasks(unkey(k), known, occupied);
    const uint64_t n = countOccupied(occupied);
    if (n == 0) {
      if (sent_.count(k) != 0) {
        if (spent + kDeletionBytes > budget_bytes && !writer.empty()) break;
        writer.deleteEntity(blockEntityId(unkey(k)));
        spent += kDeletionBytes;
        forget(k);
        ++step.deleted_blocks;
      }
      continue;
    }
    const auto sent = sent_.find(k);
    if (sent != sent_.end() && sent->second.lod == Lod::kFull && sent->second.occupied == occupied) {
      stale_.insert(k);  // the same cubes: only colours and probabilities may have moved
      continue;
    }
    const double coarse = static_cast<double>(SceneUpdateWriter::entityBytes(1));
    if (spent + coarse > budget_bytes && (!planned.empty() || !writer.empty())) break;
    planned.push_back({k, dirty[reached].first, n, n == 1});
    spent += coarse;
  }
  for (size_t i = 0; i < reached; ++i) dirty_.erase(dirty[i].second);
  for (const uint64_t k : held) dirty_.insert(k);
  // Upgrade the nearest to full detail while the budget lasts.
  for (Planned& p : planned) {
    if (p.full) continue;
    const double extra = static_cast<double>(SceneUpdateWriter::entityBytes(p.voxels) - SceneUpdateWriter::entityBytes(1));
    if (spent + extra > budget_bytes) break;
    p.full = true;
    spent += extra;
  }
  // Budget to spare once nothing is dirty: refine coarse blocks, nearest first.
  if (dirty_.empty() && coarse_ > 0) {
    std::vector<std::pair<double, uint64_t>> coarse;
    for (const auto& [k, sent] : sent_) {
      if (sent.lod == Lod::kCoarse &&
          std::none_of(planned.begin(), planned.end(), [&](const Planned& p) { return p.key == k; })) {
        coarse.emplace_back(distance2(k), k);
      }
    }
    byDistance(coarse);
    for (const auto& [d2, k] : coarse) {
      access.readBlockMasks(unkey(k), known, occupied);
      const uint64_t n = countOccupied(occupied);
      const double full = static_cast<double>(SceneUpdateWriter::entityBytes(n));
      if (spent + full > budget_bytes && (!planned.empty() || !writer.empty())) break;
      planned.push_back({k, d2, n, true});
      spent += full;
    }
  }

  // Budget still to spare: refresh stale blocks sent at least refresh_s ago, nearest first.
  if (dirty_.empty() && coarse_ == 0 && !stale_.empty()) {
    std::vector<std::pair<double, uint64_t>> stale;
    for (const uint64_t k : stale_) {
      if (time_ns >= sent_[k].time_ns + refresh_ns_) stale.emplace_back(distance2(k), k);
    }
    byDistance(stale);
    for (const auto& [d2, k] : stale) {
      access.readBlockMasks(unkey(k), known, occupied);
      const double full = static_cast<double>(SceneUpdateWriter::entityBytes(countOccupied(occupied)));
      if (spent + full > budget_bytes) break;
      planned.push_back({k, d2, countOccupied(occupied), true});
      spent += full;
    }
  }

  // Write the planned blocks as they are in the map now.
  std::vector<VoxelCube> cubes;
  std::vector<float> probabilities;
  const float voxel_m = static_cast<float>(map.voxelSize());
  for (const Planned& p : planned) {
    const mapping::BlockIndex block = unkey(p.key);
    access.readBlockMasks(block, known, occupied);
    cubes.clear();
    probabilities.clear();
    Eigen::Vector3d rgb_sum = Eigen::Vector3d::Zero();
    uint64_t n = 0;
    for (int word = 0; word < 8; ++word) {
      for (uint64_t bits = occupied[word]; bits != 0; bits &= bits - 1) {
        const int offset = word * 64 + std::countr_zero(bits);
        const mapping::VoxelIndex ijk = mapping::voxelOfOffset(block, offset);
        const Eigen::Vector3d centre = map.toPoint(ijk);
        std::array<uint8_t, 3> rgb;
        if (color_by_ == ColorBy::kHeight || !access.color(ijk, rgb)) rgb = heightColor(centre.z());
        ++n;
        if (p.full) {
          cubes.push_back({centre.cast<float>(), rgb});
          float l = 0.0f;
          access.logOdds(ijk, l);
          probabilities.push_back(static_cast<float>(mapping::probability(l)));
        } else {
          rgb_sum += Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
        }
      }
    }
    if (p.full) {
      writer.blockEntity(block, cubes, voxel_m, false, n, probabilities);
      setLevel(p.key, Lod::kFull, occupied, time_ns);
      ++step.full_blocks;
      step.full_voxels += n;
    } else {
      const Eigen::Vector3d mean = rgb_sum / static_cast<double>(std::max<uint64_t>(n, 1));
      const Eigen::Vector3d centre = (block.cast<double>().array() + 0.5).matrix() * block_m;
      cubes.push_back({centre.cast<float>(),
                       {static_cast<uint8_t>(mean.x() + 0.5), static_cast<uint8_t>(mean.y() + 0.5),
                        static_cast<uint8_t>(mean.z() + 0.5)}});
      writer.blockEntity(block, cubes, static_cast<float>(block_m), true, n, {});
      setLevel(p.key, Lod::kCoarse, occupied, time_ns);
      ++step.coarse_blocks;
    }
  }
  if (!writer.empty()) step.message = writer.finish();
  return step;
}

}  // namespace cenote::server::viewer
