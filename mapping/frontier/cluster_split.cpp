#include "mapping/frontier/cluster_split.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace cenote::mapping::detail {
namespace {

using Int128 = __int128;

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

// Moments of a set of voxels, coordinates relative to the component's reference voxel (so that
// sums stay small); exact, so they add and subtract in any order. Wide: the type of the sums of
// products, int64_t where they cannot overflow (n * extent^2 < 2^62), else Int128.
template <typename Wide>
struct Moments {
  int64_t n = 0;
  int64_t sum[3] = {0, 0, 0};
  Wide sum2[6] = {0, 0, 0, 0, 0, 0};  // xx, yy, zz, xy, xz, yz
  int64_t dir[3][3] = {};             // dir[k - 1]: sum of the integer face directions of squared norm k
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
  void extendBox(const Moments& o) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], o.lo[i]);
      hi[i] = std::max(hi[i], o.hi[i]);
    }
  }
  void add(const int32_t v[3], uint8_t faces) {
    ++n;
    for (int i = 0; i < 3; ++i) sum[i] += v[i];
    sum2[0] += static_cast<int64_t>(v[0]) * v[0];
    sum2[1] += static_cast<int64_t>(v[1]) * v[1];
    sum2[2] += static_cast<int64_t>(v[2]) * v[2];
    sum2[3] += static_cast<int64_t>(v[0]) * v[1];
    sum2[4] += static_cast<int64_t>(v[0]) * v[2];
    sum2[5] += static_cast<int64_t>(v[1]) * v[2];
    const int f = faces & 63;
    if (const int k = kFaceTable.norm2[f]; k > 0) {
      for (int i = 0; i < 3; ++i) dir[k - 1][i] += kFaceTable.d[f][i];
    }
    extendBox(v);
  }
  void merge(const Moments& o) {
    n += o.n;
    for (int i = 0; i < 3; ++i) sum[i] += o.sum[i];
    for (int i = 0; i < 6; ++i) sum2[i] += o.sum2[i];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) dir[k][i] += o.dir[k][i];
    extendBox(o);
  }
  // Counts and sums of this set minus its subset `part` (the box is not subtractable).
  void subtractSums(const Moments& part) {
    n -= part.n;
    for (int i = 0; i < 3; ++i) sum[i] -= part.sum[i];
    for (int i = 0; i < 6; ++i) sum2[i] -= part.sum2[i];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) dir[k][i] -= part.dir[k][i];
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

// The plane through the mean of a set across `axis`: a voxel is on the low side when
// (n v - sum) . axis < 0 (n times (v - mean) . axis), evaluated in this one way for every voxel.
struct Plane {
  int64_t n;
  int64_t sum[3];
  Eigen::Vector3d axis;
  double side(const int32_t r[3]) const {
    return static_cast<double>(n * r[0] - sum[0]) * axis.x() + static_cast<double>(n * r[1] - sum[1]) * axis.y() +
           static_cast<double>(n * r[2] - sum[2]) * axis.z();
  }
  // -1 when side() < 0 for every voxel of the box, +1 when side() >= 0 for every one, else 0. The
  // side is linear, so its extremes are at the corners; the margin covers rounding (relative
  // 1e-9, where a double's is 1e-16), so the answer is the one side() gives voxel by voxel.
  template <typename M>
  int classify(const M& box) const {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, scale = 0.0;
    for (int c = 0; c < 8; ++c) {
      const int32_t r[3] = {(c & 1) ? box.hi[0] : box.lo[0], (c & 2) ? box.hi[1] : box.lo[1],
                            (c & 4) ? box.hi[2] : box.lo[2]};
      const double s = side(r);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
      for (int i = 0; i < 3; ++i) scale = std::max(scale, std::abs(static_cast<double>(n * r[i] - sum[i])));
    }
    const double margin = 1e-9 * 3.0 * scale;
    if (hi < -margin) return -1;
    if (lo > margin) return 1;
    return 0;
  }
};

// A run of voxels of the array, with its moments.
template <typename Wide>
struct Chunk {
  uint32_t begin = 0, end = 0;
  Moments<Wide> m;
};

template <typename Wide>
class Splitter {
 public:
  using M = Moments<Wide>;
  using C = Chunk<Wide>;

  Splitter(FrontierVoxel* voxels, const SplitParams& params, const VoxelIndex& ref, uint64_t& next_id,
           std::vector<FrontierCluster>& out)
      : voxels_(voxels), params_(params), ref_(ref), next_id_(next_id), out_(out) {}

  void rel(const FrontierVoxel& v, int32_t r[3]) const {
    for (int i = 0; i < 3; ++i) r[i] = v.ijk[i] - ref_[i];
  }

  // Splits the set made of `chunks` (moments m) across its main axis until small enough. Chunks
  // wholly on one side of a plane go there whole; only those it cuts are split voxel by voxel.
  void split(std::vector<C>& chunks, const M& m) {
    if (m.n < params_.min_voxels) return;
    int32_t extent_voxels = 0;
    for (int i = 0; i < 3; ++i) extent_voxels = std::max(extent_voxels, m.hi[i] - m.lo[i] + 1);
    if (extent_voxels * params_.voxel_size_m > params_.max_extent_m && m.n >= 2) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m.scaledCovariance());
      const Plane plane{m.n, {m.sum[0], m.sum[1], m.sum[2]}, eig.eigenvectors().col(2)};
      std::vector<C> low, high;
      M a, b_box;
      for (const C& c : chunks) {
        const int where = plane.classify(c.m);
        if (where < 0) {
          a.merge(c.m);
          low.push_back(c);
        } else if (where > 0) {
          b_box.extendBox(c.m);
          high.push_back(c);
        } else {
          C ca, cb;
          cut(c, plane, ca, cb);
          if (ca.m.n > 0) {
            a.merge(ca.m);
            low.push_back(ca);
          }
          if (cb.m.n > 0) {
            b_box.extendBox(cb.m);
            high.push_back(cb);
          }
        }
      }
      if (a.n > 0 && a.n < m.n) {
        M b = m;
        b.subtractSums(a);
        std::copy(b_box.lo, b_box.lo + 3, b.lo);
        std::copy(b_box.hi, b_box.hi + 3, b.hi);
        chunks = std::vector<C>();
        split(low, a);
        split(high, b);
        return;
      }
    }
    emit(m);
  }

 private:
  // Cuts one chunk by the plane, voxel by voxel, in place: ca the low side, cb the rest.
  void cut(const C& c, const Plane& plane, C& ca, C& cb) {
    FrontierVoxel* i = voxels_ + c.begin;
    FrontierVoxel* j = voxels_ + c.end;
    while (i < j) {
      int32_t r[3];
      rel(*i, r);
      if (plane.side(r) < 0.0) {
        ca.m.add(r, i->faces);
        ++i;
      } else {
        cb.m.extendBox(r);
        std::swap(*i, *--j);
      }
    }
    const uint32_t mid = static_cast<uint32_t>(i - voxels_);
    ca.begin = c.begin;
    ca.end = mid;
    cb.begin = mid;
    cb.end = c.end;
    const M box = cb.m;
    cb.m = c.m;
    cb.m.subtractSums(ca.m);
    std::copy(box.lo, box.lo + 3, cb.m.lo);
    std::copy(box.hi, box.hi + 3, cb.m.hi);
  }

  void emit(const M& m) {
    const double s = params_.voxel_size_m;
    FrontierCluster c;
    c.id = next_id_++;
    c.num_voxels = static_cast<size_t>(m.n);
    for (int i = 0; i < 3; ++i) {
      c.centroid_m[i] = (ref_[i] + static_cast<double>(m.sum[i]) / static_cast<double>(m.n) + 0.5) * s;
      c.bounds_m.min_m[i] = static_cast<double>(ref_[i] + m.lo[i]) * s;
      c.bounds_m.max_m[i] = (static_cast<double>(ref_[i] + m.hi[i]) + 1.0) * s;
      // Sum of the voxels' unit directions: the integer sums of norm 1, sqrt 2 and sqrt 3.
      c.direction[i] = static_cast<double>(m.dir[0][i]) + static_cast<double>(m.dir[1][i]) / std::sqrt(2.0) +
                       static_cast<double>(m.dir[2][i]) / std::sqrt(3.0);
    }
    if (c.direction.norm() > 0.0) c.direction.normalize();
    out_.push_back(c);
  }

  FrontierVoxel* voxels_;
  const SplitParams& params_;
  const VoxelIndex ref_;
  uint64_t& next_id_;
  std::vector<FrontierCluster>& out_;
};

template <typename Wide>
void splitWith(std::vector<FrontierVoxel>& voxels, const std::vector<uint32_t>& chunk_ends, const SplitParams& params,
               const VoxelIndex& ref, uint64_t& next_id, std::vector<FrontierCluster>& out) {
  Splitter<Wide> splitter(voxels.data(), params, ref, next_id, out);
  std::vector<Chunk<Wide>> chunks;
  Moments<Wide> all;
  uint32_t begin = 0;
  for (uint32_t end : chunk_ends) {
    if (end <= begin) continue;
    Chunk<Wide> c;
    c.begin = begin;
    c.end = end;
    for (uint32_t k = begin; k < end; ++k) {
      int32_t r[3];
      splitter.rel(voxels[k], r);
      c.m.add(r, voxels[k].faces);
    }
    all.merge(c.m);
    chunks.push_back(c);
    begin = end;
  }
  splitter.split(chunks, all);
}

}  // namespace

void splitComponent(std::vector<FrontierVoxel>& voxels, const std::vector<uint32_t>& chunk_ends,
                    const SplitParams& params, uint64_t& next_id, std::vector<FrontierCluster>& out) {
  if (voxels.empty() || static_cast<int64_t>(voxels.size()) < params.min_voxels) return;
  // Reference: the component's lowest corner, which does not depend on the voxels' order.
  VoxelIndex ref = voxels.front().ijk;
  for (const FrontierVoxel& v : voxels) ref = ref.cwiseMin(v.ijk);
  int64_t extent = 0;
  for (const FrontierVoxel& v : voxels) extent = std::max<int64_t>(extent, (v.ijk - ref).maxCoeff());
  std::vector<uint32_t> whole;
  const std::vector<uint32_t>* ends = &chunk_ends;
  if (chunk_ends.empty() || chunk_ends.back() != voxels.size()) {
    whole.assign(1, static_cast<uint32_t>(voxels.size()));
    ends = &whole;
  }
  // |sums of products| <= n * extent^2; extent < 2^22 and n < 2^32, so Int128 never overflows.
  const bool fits_int64 = static_cast<double>(voxels.size()) * static_cast<double>(extent) * extent < 0x1p62;
  if (fits_int64) {
    splitWith<int64_t>(voxels, *ends, params, ref, next_id, out);
  } else {
    splitWith<Int128>(voxels, *ends, params, ref, next_id, out);
  }
}

void splitComponent(std::vector<FrontierVoxel>& voxels, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out) {
  splitComponent(voxels, {}, params, next_id, out);
}

}  // namespace cenote::mapping::detail
