#include "mapping/frontier/cluster_split.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace cenote::mapping::detail {
namespace {

using Int128 = __int128;

// Moments of a set of voxels, coordinates relative to the component's reference voxel (so that
// sums stay small); exact, so they add and subtract in any order. Wide: the type of the sums of
// products, int64_t where they cannot overflow (n * extent^2 < 2^62), else Int128.
template <typename Wide>
struct Moments {
  int64_t n = 0;
  int64_t sum[3] = {0, 0, 0};
  Wide sum2[6] = {0, 0, 0, 0, 0, 0};  // xx, yy, zz, xy, xz, yz
  int32_t lo[3] = {std::numeric_limits<int32_t>::max(), std::numeric_limits<int32_t>::max(),
                   std::numeric_limits<int32_t>::max()};
  int32_t hi[3] = {std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::min(),
                   std::numeric_limits<int32_t>::min()};

  void extendBox(const int32_t v[3]) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], v[i]);
      hi[i] = std::max(hi[i], v[i]);
    }
  }
  void add(const int32_t v[3]) {
    ++n;
    for (int i = 0; i < 3; ++i) sum[i] += v[i];
    sum2[0] += static_cast<int64_t>(v[0]) * v[0];
    sum2[1] += static_cast<int64_t>(v[1]) * v[1];
    sum2[2] += static_cast<int64_t>(v[2]) * v[2];
    sum2[3] += static_cast<int64_t>(v[0]) * v[1];
    sum2[4] += static_cast<int64_t>(v[0]) * v[2];
    sum2[5] += static_cast<int64_t>(v[1]) * v[2];
    extendBox(v);
  }
  // Counts and sums of this set minus its subset `part` (the box is not subtractable).
  void subtractSums(const Moments& part) {
    n -= part.n;
    for (int i = 0; i < 3; ++i) sum[i] -= part.sum[i];
    for (int i = 0; i < 6; ++i) sum2[i] -= part.sum2[i];
  }
  // n^2 times the covariance: n * sum(v v^T) - sum(v) sum(v)^T, exact before the conversion.
  Eigen::Matrix3d scaledCovariance() const {
    auto c = [&](int k, int i, int j) { return static_cast<double>(Int128(n) * sum2[k] - Int128(sum[i]) * sum[j]); };
    Eigen::Matrix3d m;
    m(0, 0) = c(0, 0, 0);
    m(1, 1) = c(1, 1, 1);
    m(2, 2) = c(2, 2, 2);
    m(0, 1) = m(1, 0) = c(3, 0, 1);
    m(0, 2) = m(2, 0) = c(4, 0, 2);
    m(1, 2) = m(2, 1) = c(5, 1, 2);
    return m;
  }
};

// Integer direction into the unknown of each face set (bit i: kFaceOffsets[i]; opposite faces
// cancel) and its squared norm, 0..3.
struct FaceTable {
  int8_t d[64][3];
  int8_t norm2[64];
  FaceTable() {
    for (int f = 0; f < 64; ++f) {
      d[f][0] = static_cast<int8_t>((f & 1) - ((f >> 1) & 1));
      d[f][1] = static_cast<int8_t>(((f >> 2) & 1) - ((f >> 3) & 1));
      d[f][2] = static_cast<int8_t>(((f >> 4) & 1) - ((f >> 5) & 1));
      norm2[f] = static_cast<int8_t>(d[f][0] * d[f][0] + d[f][1] * d[f][1] + d[f][2] * d[f][2]);
    }
  }
};
const FaceTable kFaceTable;

template <typename Wide>
class Splitter {
 public:
  using Moments = cenote::mapping::detail::Moments<Wide>;

  Splitter(const SplitParams& params, const VoxelIndex& ref, uint64_t& next_id, std::vector<FrontierCluster>& out)
      : params_(params), ref_(ref), next_id_(next_id), out_(out) {}

  void rel(const FrontierVoxel& v, int32_t r[3]) const {
    for (int i = 0; i < 3; ++i) r[i] = v.ijk[i] - ref_[i];
  }

  void split(FrontierVoxel* begin, FrontierVoxel* end, const Moments& m) {
    if (m.n < params_.min_voxels) return;
    int32_t extent_voxels = 0;
    for (int i = 0; i < 3; ++i) extent_voxels = std::max(extent_voxels, m.hi[i] - m.lo[i] + 1);
    if (extent_voxels * params_.voxel_size_m > params_.max_extent_m && m.n >= 2) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m.scaledCovariance());
      const Eigen::Vector3d axis = eig.eigenvectors().col(2);
      // Side of the plane through the mean: sign of (n v - sum) . axis, n times (v - mean) . axis.
      Moments a, b_box;
      FrontierVoxel* i = begin;
      FrontierVoxel* j = end;
      while (i < j) {
        int32_t r[3];
        rel(*i, r);
        const double side = static_cast<double>(m.n * r[0] - m.sum[0]) * axis.x() +
                            static_cast<double>(m.n * r[1] - m.sum[1]) * axis.y() +
                            static_cast<double>(m.n * r[2] - m.sum[2]) * axis.z();
        if (side < 0.0) {
          a.add(r);
          ++i;
        } else {
          b_box.extendBox(r);
          std::swap(*i, *--j);
        }
      }
      if (a.n > 0 && a.n < m.n) {
        Moments b = m;
        b.subtractSums(a);
        std::copy(b_box.lo, b_box.lo + 3, b.lo);
        std::copy(b_box.hi, b_box.hi + 3, b.hi);
        split(begin, i, a);
        split(i, end, b);
        return;
      }
    }
    emit(begin, end, m);
  }

 private:
  void emit(const FrontierVoxel* begin, const FrontierVoxel* end, const Moments& m) {
    const double s = params_.voxel_size_m;
    FrontierCluster c;
    c.id = next_id_++;
    c.num_voxels = static_cast<size_t>(m.n);
    for (int i = 0; i < 3; ++i) {
      c.centroid_m[i] = (ref_[i] + static_cast<double>(m.sum[i]) / static_cast<double>(m.n) + 0.5) * s;
      c.bounds_m.min_m[i] = static_cast<double>(ref_[i] + m.lo[i]) * s;
      c.bounds_m.max_m[i] = (static_cast<double>(ref_[i] + m.hi[i]) + 1.0) * s;
    }
    // Sum of the voxels' unit directions, grouped by norm (1, sqrt 2, sqrt 3) in integers.
    int64_t by_norm[4][3] = {};
    for (const FrontierVoxel* v = begin; v != end; ++v) {
      const int f = v->faces & 63;
      int64_t* acc = by_norm[kFaceTable.norm2[f]];
      for (int i = 0; i < 3; ++i) acc[i] += kFaceTable.d[f][i];
    }
    for (int i = 0; i < 3; ++i) {
      c.direction[i] = static_cast<double>(by_norm[1][i]) + static_cast<double>(by_norm[2][i]) / std::sqrt(2.0) +
                       static_cast<double>(by_norm[3][i]) / std::sqrt(3.0);
    }
    if (c.direction.norm() > 0.0) c.direction.normalize();
    out_.push_back(c);
  }

  const SplitParams& params_;
  const VoxelIndex ref_;
  uint64_t& next_id_;
  std::vector<FrontierCluster>& out_;
};

template <typename Wide>
void splitWith(std::vector<FrontierVoxel>& voxels, const SplitParams& params, const VoxelIndex& ref, uint64_t& next_id,
               std::vector<FrontierCluster>& out) {
  Splitter<Wide> splitter(params, ref, next_id, out);
  Moments<Wide> all;
  for (const FrontierVoxel& v : voxels) {
    int32_t r[3];
    splitter.rel(v, r);
    all.add(r);
  }
  splitter.split(voxels.data(), voxels.data() + voxels.size(), all);
}

}  // namespace

void splitComponent(std::vector<FrontierVoxel>& voxels, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out) {
  if (voxels.empty() || static_cast<int64_t>(voxels.size()) < params.min_voxels) return;
  // Reference: the component's lowest corner, which does not depend on the voxels' order.
  VoxelIndex ref = voxels.front().ijk;
  for (const FrontierVoxel& v : voxels) ref = ref.cwiseMin(v.ijk);
  int64_t extent = 0;
  for (const FrontierVoxel& v : voxels) extent = std::max<int64_t>(extent, (v.ijk - ref).maxCoeff());
  // |sums of products| <= n * extent^2; extent < 2^22 and n < 2^32, so Int128 never overflows.
  const bool fits_int64 = static_cast<double>(voxels.size()) * static_cast<double>(extent) * extent < 0x1p62;
  if (fits_int64) {
    splitWith<int64_t>(voxels, params, ref, next_id, out);
  } else {
    splitWith<Int128>(voxels, params, ref, next_id, out);
  }
}

}  // namespace cenote::mapping::detail
