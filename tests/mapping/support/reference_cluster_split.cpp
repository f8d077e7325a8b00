#include "tests/mapping/support/reference_cluster_split.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace cenote::mapping::test {
namespace {

// Count, sums and bounding box of a part, taken voxel by voxel.
struct PartSums {
  int64_t n = 0;
  int64_t sum[3] = {0, 0, 0};
  int64_t sum2[3][3] = {};
  VoxelIndex lo = VoxelIndex::Constant(1 << 30);
  VoxelIndex hi = VoxelIndex::Constant(-(1 << 30));
};

PartSums sumsOf(const std::vector<ReferenceVoxel>& part) {
  PartSums s;
  for (const ReferenceVoxel& v : part) {
    ++s.n;
    for (int i = 0; i < 3; ++i) {
      s.sum[i] += v.ijk[i];
      for (int j = 0; j < 3; ++j) s.sum2[i][j] += int64_t{v.ijk[i]} * v.ijk[j];
    }
    s.lo = s.lo.cwiseMin(v.ijk);
    s.hi = s.hi.cwiseMax(v.ijk);
  }
  return s;
}

// n^2 times the covariance, n sum(v v^T) - sum(v) sum(v)^T. Taken exactly (integers, then one
// conversion): the sign of the eigenvector Eigen returns decides where voxels on the plane go, and
// it can flip when an entry that is exactly zero carries rounding noise instead.
Eigen::Matrix3d scaledCovariance(const PartSums& s) {
  Eigen::Matrix3d c;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i, j) = static_cast<double>(s.n * s.sum2[i][j] - s.sum[i] * s.sum[j]);
  return c;
}

ReferenceCluster clusterOf(const std::vector<ReferenceVoxel>& part, const PartSums& s, double voxel_size_m) {
  ReferenceCluster c;
  c.voxels = part;
  Eigen::Vector3d centre_sum = Eigen::Vector3d::Zero();
  for (const ReferenceVoxel& v : part) {
    centre_sum += (v.ijk.cast<double>() + Eigen::Vector3d::Constant(0.5)) * voxel_size_m;
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (int f = 0; f < 6; ++f) {
      if ((v.faces >> f) & 1) d += kReferenceFaceOffsets[f].cast<double>();
    }
    if (d.norm() > 0.0) c.direction += d.normalized();
  }
  c.centroid_m = centre_sum / static_cast<double>(s.n);
  if (c.direction.norm() > 0.0) c.direction.normalize();
  c.bounds_m.min_m = s.lo.cast<double>() * voxel_size_m;
  c.bounds_m.max_m = (s.hi + VoxelIndex::Ones()).cast<double>() * voxel_size_m;
  return c;
}

void split(const std::vector<ReferenceVoxel>& part, double voxel_size_m, double max_extent_m, int min_voxels,
           std::vector<ReferenceCluster>& out) {
  const PartSums s = sumsOf(part);
  if (s.n < min_voxels) return;
  // Split while the box's longest side exceeds max_extent_m, counted in whole voxels (a side of
  // exactly max_extent_m stays, whatever 6 x 0.1 rounds to in double).
  const int extent_voxels = (s.hi - s.lo + VoxelIndex::Ones()).maxCoeff();
  const int max_voxels = static_cast<int>(std::floor(max_extent_m / voxel_size_m + 1e-9));
  if (s.n >= 2 && extent_voxels > max_voxels) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scaledCovariance(s));
    const Eigen::Vector3d axis = eig.eigenvectors().col(2);  // eigenvalues ascend: the largest
    std::vector<ReferenceVoxel> low, high;
    for (const ReferenceVoxel& v : part) {
      double side = 0.0;  // n (v - mean) . axis
      for (int i = 0; i < 3; ++i) side += static_cast<double>(s.n * v.ijk[i] - s.sum[i]) * axis[i];
      (side < 0.0 ? low : high).push_back(v);
    }
    if (!low.empty() && !high.empty()) {
      split(low, voxel_size_m, max_extent_m, min_voxels, out);
      split(high, voxel_size_m, max_extent_m, min_voxels, out);
      return;
    }
  }
  out.push_back(clusterOf(part, s, voxel_size_m));
}

}  // namespace

void referenceSplitComponent(const std::vector<ReferenceVoxel>& component, double voxel_size_m, double max_extent_m,
                             int min_voxels, std::vector<ReferenceCluster>& out) {
  split(component, voxel_size_m, max_extent_m, min_voxels, out);
}

}  // namespace cenote::mapping::test
