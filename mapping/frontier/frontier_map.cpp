#include "mapping/frontier/frontier_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <mutex>
#include <unordered_map>
#include <unordered_set>

#include "mapping/detail/block_table.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

const VoxelIndex kFaces[6] = {VoxelIndex(1, 0, 0),  VoxelIndex(-1, 0, 0), VoxelIndex(0, 1, 0),
                              VoxelIndex(0, -1, 0), VoxelIndex(0, 0, 1),  VoxelIndex(0, 0, -1)};

struct Component {
  std::vector<VoxelIndex> voxels;
  std::vector<FrontierCluster> clusters;
};

}  // namespace

struct FrontierMap::Impl {
  std::optional<Aabb> roi;
  std::unordered_map<uint64_t, uint64_t> frontier;  // voxel -> component id
  std::unordered_map<uint64_t, Component> components;
  uint64_t next_component = 1;
  uint64_t next_cluster = 1;
  int min_voxels = 10;
  double max_extent_m = 2.0;
  double s = 0.05;

  // Unit direction from a frontier voxel into its unknown face neighbours.
  Eigen::Vector3d unknownDirection(const OccupancyMap::ConstAccessor& acc, const VoxelIndex& v) const {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (const VoxelIndex& f : kFaces) {
      if (acc.state(v + f) == VoxelState::kUnknown) d += f.cast<double>();
    }
    const double n = d.norm();
    return n > 0.0 ? Eigen::Vector3d(d / n) : d;
  }

  bool isFrontier(const OccupancyMap::ConstAccessor& acc, const VoxelIndex& v) const {
    if (acc.state(v) != VoxelState::kFree) return false;
    if (roi && !roi->contains(voxelCentre(v, s))) return false;
    for (const VoxelIndex& f : kFaces) {
      if (acc.state(v + f) == VoxelState::kUnknown) return true;
    }
    return false;
  }

  // Splits voxels along their main axis until small enough; appends clusters of >= min_voxels.
  void split(const OccupancyMap::ConstAccessor& acc, std::vector<VoxelIndex> voxels, std::vector<FrontierCluster>& out) {
    if (static_cast<int>(voxels.size()) < min_voxels) return;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    VoxelBox box;
    for (const auto& v : voxels) {
      mean += voxelCentre(v, s);
      box.extend(v);
    }
    mean /= static_cast<double>(voxels.size());
    const double extent_m = ((box.max - box.min).cast<double>().array() + 1.0).maxCoeff() * s;
    if (extent_m > max_extent_m && voxels.size() >= 2) {
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const auto& v : voxels) {
        const Eigen::Vector3d d = voxelCentre(v, s) - mean;
        cov += d * d.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      const Eigen::Vector3d axis = eig.eigenvectors().col(2);
      std::vector<VoxelIndex> a, b;
      for (const auto& v : voxels) ((voxelCentre(v, s) - mean).dot(axis) < 0.0 ? a : b).push_back(v);
      if (!a.empty() && !b.empty()) {
        split(acc, std::move(a), out);
        split(acc, std::move(b), out);
        return;
      }
    }
    FrontierCluster c;
    c.id = next_cluster++;
    c.num_voxels = voxels.size();
    c.centroid_m = mean;
    c.bounds_m.min_m = box.min.cast<double>() * s;
    c.bounds_m.max_m = (box.max.cast<double>().array() + 1.0).matrix() * s;
    for (const auto& v : voxels) c.direction += unknownDirection(acc, v);
    if (c.direction.norm() > 0.0) c.direction.normalize();
    out.push_back(c);
  }

  void apply(const OccupancyMap& map, const std::vector<BlockIndex>& blocks) {
    const auto acc = map.constAccessor();
    std::unordered_set<uint64_t> dirty_components;
    std::vector<VoxelIndex> seeds;
    std::unordered_set<uint64_t> examined;
    auto touch = [&](const VoxelIndex& v) {
      const uint64_t key = detail::packIndex(v);
      if (!examined.insert(key).second) return;
      const bool now = isFrontier(acc, v);
      const auto it = frontier.find(key);
      if (it != frontier.end()) {
        dirty_components.insert(it->second);
        if (!now) frontier.erase(it);
      } else if (now) {
        frontier.emplace(key, 0);
      }
      if (now) seeds.push_back(v);
    };
    for (const BlockIndex& block : blocks) {
      const VoxelIndex base = block * kBlockSide;
      for (int x = -1; x <= kBlockSide; ++x)
        for (int y = -1; y <= kBlockSide; ++y)
          for (int z = -1; z <= kBlockSide; ++z) touch(base + VoxelIndex(x, y, z));
    }
    // Components touching the changed region are rebuilt from their remaining voxels and the seeds.
    for (uint64_t id : dirty_components) {
      auto it = components.find(id);
      if (it == components.end()) continue;
      for (const auto& v : it->second.voxels) {
        const auto f = frontier.find(detail::packIndex(v));
        if (f != frontier.end()) {
          f->second = 0;
          seeds.push_back(v);
        }
      }
      components.erase(it);
    }
    for (const VoxelIndex& seed : seeds) {
      auto f = frontier.find(detail::packIndex(seed));
      if (f == frontier.end() || f->second != 0) continue;
      const uint64_t id = next_component++;
      Component comp;
      std::vector<VoxelIndex> stack{seed};
      f->second = id;
      while (!stack.empty()) {
        const VoxelIndex v = stack.back();
        stack.pop_back();
        comp.voxels.push_back(v);
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              const VoxelIndex n = v + VoxelIndex(dx, dy, dz);
              auto nf = frontier.find(detail::packIndex(n));
              if (nf == frontier.end() || nf->second == id) continue;
              if (nf->second != 0) {
                // Reached an untouched component: absorb it.
                auto old = components.find(nf->second);
                if (old != components.end()) {
                  for (const auto& w : old->second.voxels) {
                    auto wf = frontier.find(detail::packIndex(w));
                    if (wf != frontier.end() && wf->second == old->first) wf->second = 0;
                  }
                  components.erase(old);
                }
              }
              nf->second = id;
              stack.push_back(n);
            }
      }
      split(acc, comp.voxels, comp.clusters);
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
  impl_->frontier.clear();
  impl_->components.clear();
  impl_->apply(map_, map_.constAccessor().knownBlocks());
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
  return impl_->frontier.size();
}

}  // namespace cenote::mapping
