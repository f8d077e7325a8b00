#include "mapping/frontier/cluster_split.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace cenote::mapping::detail {
namespace {

using Int128 = __int128;

// Sums of small non-negative terms, several at once: 12-bit fields in a 64-bit word, added with
// one integer add (no field may reach 2^12).
constexpr int kFieldBits = 12;
constexpr uint64_t kFieldMask = (1u << kFieldBits) - 1;
constexpr int field(uint64_t packed, int j) { return static_cast<int>((packed >> (kFieldBits * j)) & kFieldMask); }

// Integer direction into the unknown of each face set (bit i: kFaceOffsets[i]; opposite faces
// cancel) and its squared norm, 0..3. packed_dir: the same as Moments::dir of one voxel, 1 added
// to each of its 9 entries (so that no field is negative): entry 3 (k - 1) + i in field (entry %
// 5) of word (entry / 5); summed over at most 512 voxels each field stays below 2^12.
struct FaceTable {
  int8_t d[64][3];
  int8_t norm2[64];
  uint64_t packed_dir[64][2];
  FaceTable() {
    for (int f = 0; f < 64; ++f) {
      d[f][0] = static_cast<int8_t>((f & 1) - ((f >> 1) & 1));
      d[f][1] = static_cast<int8_t>(((f >> 2) & 1) - ((f >> 3) & 1));
      d[f][2] = static_cast<int8_t>(((f >> 4) & 1) - ((f >> 5) & 1));
      norm2[f] = static_cast<int8_t>(d[f][0] * d[f][0] + d[f][1] * d[f][1] + d[f][2] * d[f][2]);
      packed_dir[f][0] = packed_dir[f][1] = 0;
      for (int entry = 0; entry < 9; ++entry) {
        const int k = entry / 3 + 1, i = entry % 3;
        const uint64_t value = 1 + (norm2[f] == k ? d[f][i] : 0);
        packed_dir[f][entry / 5] |= value << (kFieldBits * (entry % 5));
      }
    }
  }
};
const FaceTable kFaceTable;

// y, z, y^2, z^2 and y z of each bit y * 8 + z of a block's word, in fields 0..4: summed over the
// word's 64 bits each stays below 64 * 49 < 2^12.
struct SliceTerms {
  uint64_t packed[64];
  SliceTerms() {
    for (uint64_t o = 0; o < 64; ++o) {
      const uint64_t y = o >> 3, z = o & 7;
      packed[o] = y | z << kFieldBits | (y * y) << (2 * kFieldBits) | (z * z) << (3 * kFieldBits) |
                  (y * z) << (4 * kFieldBits);
    }
  }
};
const SliceTerms kSliceTerms;

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
  // Adds a run whose voxels lie at d + (its relative coordinates): the sums shifted by d, exactly
  // (sum (d + l)(d + l)^T = sum l l^T + d sum l^T + sum l d^T + n d d^T).
  void mergeRun(const RunMoments& r, const int64_t d[3]) {
    const int64_t rn = r.n;
    n += rn;
    for (int i = 0; i < 3; ++i) sum[i] += r.sum[i] + rn * d[i];
    constexpr int kI[6] = {0, 1, 2, 0, 0, 1}, kJ[6] = {0, 1, 2, 1, 2, 2};  // sum2's order
    for (int k = 0; k < 6; ++k) {
      const int i = kI[k], j = kJ[k];
      // |each term| <= 2^9 * 2^21 * 2^21 for a block's run within the map's +-2^20: int64 is exact.
      sum2[k] += Wide(int64_t{r.sum2[k]} + d[i] * r.sum[j] + d[j] * r.sum[i] + rn * d[i] * d[j]);
    }
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) dir[k][i] += r.dir[k][i];
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], static_cast<int32_t>(d[i] + r.lo[i]));
      hi[i] = std::max(hi[i], static_cast<int32_t>(d[i] + r.hi[i]));
    }
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
  // side is linear, so its extremes are at the two corners picked per axis by the sign of the axis
  // component; the margin covers rounding (relative 1e-9, where a double's is 1e-16), so the answer
  // is the one side() gives voxel by voxel.
  template <typename M>
  int classify(const M& box) const {
    int32_t low[3], high[3];
    double scale = 0.0;
    for (int i = 0; i < 3; ++i) {
      const bool rising = axis[i] >= 0.0;
      low[i] = rising ? box.lo[i] : box.hi[i];
      high[i] = rising ? box.hi[i] : box.lo[i];
      scale = std::max(scale, std::max(std::abs(static_cast<double>(n * box.lo[i] - sum[i])),
                                       std::abs(static_cast<double>(n * box.hi[i] - sum[i]))));
    }
    const double margin = 1e-9 * 3.0 * scale;
    if (side(high) < -margin) return -1;
    if (side(low) > margin) return 1;
    return 0;
  }
};

// Voxels [begin, end) of the listed voxels, or the voxels of a block run not listed yet; with
// their moments.
template <typename Wide>
struct Chunk {
  uint32_t begin = 0, end = 0;
  int32_t run = -1;  // >= 0: the run's index, its voxels not listed yet
  Moments<Wide> m;
};

template <typename Wide>
class Splitter {
 public:
  using M = Moments<Wide>;
  using C = Chunk<Wide>;

  // runs: those chunks with run >= 0 refer to (may be null when there are none).
  Splitter(std::vector<FrontierVoxel>& voxels, const std::vector<BlockRun>* runs, const SplitParams& params,
           const VoxelIndex& ref, uint64_t& next_id, std::vector<FrontierCluster>& out)
      : voxels_(voxels), runs_(runs), params_(params), ref_(ref), next_id_(next_id), out_(out) {}

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
  // Cuts one chunk by the plane, voxel by voxel, in place (a run's voxels are listed first): ca
  // the low side, cb the rest.
  void cut(C c, const Plane& plane, C& ca, C& cb) {
    if (c.run >= 0) list(c);
    FrontierVoxel* const first = voxels_.data();
    FrontierVoxel* i = first + c.begin;
    FrontierVoxel* j = first + c.end;
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
    const uint32_t mid = static_cast<uint32_t>(i - first);
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

  // Appends the voxels of the chunk's run to the list; the chunk becomes that range.
  void list(C& c) {
    const BlockRun& run = (*runs_)[c.run];
    c.begin = static_cast<uint32_t>(voxels_.size());
    for (int w = 0; w < 8; ++w) {
      for (uint64_t rest = (*run.bits)[w]; rest != 0; rest &= rest - 1) {
        const int o = w * 64 + __builtin_ctzll(rest);
        voxels_.push_back({voxelOfOffset(run.block, o), (*run.faces)[o]});
      }
    }
    c.end = static_cast<uint32_t>(voxels_.size());
    c.run = -1;
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

  std::vector<FrontierVoxel>& voxels_;
  const std::vector<BlockRun>* runs_;
  const SplitParams& params_;
  const VoxelIndex ref_;
  uint64_t& next_id_;
  std::vector<FrontierCluster>& out_;
};

// One chunk per run, its moments shifted from the run's block to `ref`; no voxel listed yet.
template <typename Wide>
void splitWith(const std::vector<BlockRun>& runs, const SplitParams& params, const VoxelIndex& ref, uint64_t& next_id,
               std::vector<FrontierVoxel>& scratch, std::vector<FrontierCluster>& out) {
  scratch.clear();
  Splitter<Wide> splitter(scratch, &runs, params, ref, next_id, out);
  std::vector<Chunk<Wide>> chunks;
  chunks.reserve(runs.size());
  Moments<Wide> all;
  for (size_t r = 0; r < runs.size(); ++r) {
    const BlockRun& run = runs[r];
    if (run.moments->n == 0) continue;
    Chunk<Wide> c;
    c.run = static_cast<int32_t>(r);
    const VoxelIndex origin = run.block * kBlockSide;
    const int64_t d[3] = {int64_t{origin.x()} - ref.x(), int64_t{origin.y()} - ref.y(), int64_t{origin.z()} - ref.z()};
    c.m.mergeRun(*run.moments, d);
    all.merge(c.m);
    chunks.push_back(c);
  }
  splitter.split(chunks, all);
}

// The whole component as one chunk, its moments summed voxel by voxel.
template <typename Wide>
void splitWith(std::vector<FrontierVoxel>& voxels, const SplitParams& params, const VoxelIndex& ref,
               uint64_t& next_id, std::vector<FrontierCluster>& out) {
  Splitter<Wide> splitter(voxels, nullptr, params, ref, next_id, out);
  std::vector<Chunk<Wide>> chunks(1);
  chunks[0].end = static_cast<uint32_t>(voxels.size());
  for (const FrontierVoxel& v : voxels) {
    int32_t r[3];
    splitter.rel(v, r);
    chunks[0].m.add(r, v.faces);
  }
  const Moments<Wide> all = chunks[0].m;
  splitter.split(chunks, all);
}

// |sums of products| <= n * extent^2; extent < 2^22 and n < 2^32, so Int128 never overflows.
bool sumsFitInt64(size_t num_voxels, int64_t extent) {
  return static_cast<double>(num_voxels) * static_cast<double>(extent) * static_cast<double>(extent) < 0x1p62;
}

}  // namespace

RunMoments blockRunMoments(const BlockMask& bits, const std::array<uint8_t, kBlockVoxels>& faces) {
  RunMoments m;
  uint64_t dir[2] = {0, 0};  // FaceTable::packed_dir summed
  uint64_t all = 0;          // the yz-pattern of every x slice
  bool first = true;
  for (int x = 0; x < 8; ++x) {
    if (bits[x] == 0) continue;
    // The x slice (word x, bit y * 8 + z): its count and packed sums, then weighted by x.
    int count = 0;
    uint64_t terms = 0;
    for (uint64_t rest = bits[x]; rest != 0; rest &= rest - 1) {
      const int o = __builtin_ctzll(rest);
      ++count;
      terms += kSliceTerms.packed[o];
      const int f = faces[x * 64 + o] & 63;
      dir[0] += kFaceTable.packed_dir[f][0];
      dir[1] += kFaceTable.packed_dir[f][1];
    }
    const int sy = field(terms, 0), sz = field(terms, 1);
    m.n += count;
    m.sum[0] += x * count;
    m.sum[1] += sy;
    m.sum[2] += sz;
    m.sum2[0] += x * x * count;
    m.sum2[1] += field(terms, 2);
    m.sum2[2] += field(terms, 3);
    m.sum2[3] += x * sy;
    m.sum2[4] += x * sz;
    m.sum2[5] += field(terms, 4);
    all |= bits[x];
    if (first) m.lo[0] = static_cast<int8_t>(x);
    m.hi[0] = static_cast<int8_t>(x);
    first = false;
  }
  for (int entry = 0; entry < 9; ++entry) m.dir[entry / 3][entry % 3] = field(dir[entry / 5], entry % 5) - m.n;
  if (all == 0) return m;
  // y: the non-zero bytes of `all`; z: the bits of its bytes OR-ed together.
  uint64_t rows = 0;
  for (int y = 0; y < 8; ++y) rows |= static_cast<uint64_t>(((all >> (8 * y)) & 0xFF) != 0) << y;
  uint64_t columns = all | (all >> 32);
  columns |= columns >> 16;
  columns |= columns >> 8;
  columns &= 0xFF;
  m.lo[1] = static_cast<int8_t>(__builtin_ctzll(rows));
  m.hi[1] = static_cast<int8_t>(63 - __builtin_clzll(rows));
  m.lo[2] = static_cast<int8_t>(__builtin_ctzll(columns));
  m.hi[2] = static_cast<int8_t>(63 - __builtin_clzll(columns));
  return m;
}

void splitComponent(const std::vector<BlockRun>& runs, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierVoxel>& scratch, std::vector<FrontierCluster>& out) {
  int64_t n = 0;
  for (const BlockRun& run : runs) n += run.moments->n;
  if (n == 0 || n < params.min_voxels) return;
  // The same reference and extent as from the voxels, from the runs' boxes.
  VoxelIndex ref = VoxelIndex::Constant(std::numeric_limits<int>::max());
  for (const BlockRun& run : runs) {
    if (run.moments->n == 0) continue;
    for (int i = 0; i < 3; ++i) ref[i] = std::min(ref[i], run.block[i] * kBlockSide + run.moments->lo[i]);
  }
  int64_t extent = 0;
  for (const BlockRun& run : runs) {
    if (run.moments->n == 0) continue;
    for (int i = 0; i < 3; ++i) {
      extent = std::max<int64_t>(extent, run.block[i] * kBlockSide + run.moments->hi[i] - ref[i]);
    }
  }
  if (sumsFitInt64(static_cast<size_t>(n), extent)) {
    splitWith<int64_t>(runs, params, ref, next_id, scratch, out);
  } else {
    splitWith<Int128>(runs, params, ref, next_id, scratch, out);
  }
}

void splitComponent(std::vector<FrontierVoxel>& voxels, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out) {
  if (voxels.empty() || static_cast<int64_t>(voxels.size()) < params.min_voxels) return;
  // Reference: the component's lowest corner, which does not depend on the voxels' order.
  VoxelIndex ref = voxels.front().ijk;
  for (const FrontierVoxel& v : voxels) ref = ref.cwiseMin(v.ijk);
  int64_t extent = 0;
  for (const FrontierVoxel& v : voxels) extent = std::max<int64_t>(extent, (v.ijk - ref).maxCoeff());
  if (sumsFitInt64(voxels.size(), extent)) {
    splitWith<int64_t>(voxels, params, ref, next_id, out);
  } else {
    splitWith<Int128>(voxels, params, ref, next_id, out);
  }
}

}  // namespace cenote::mapping::detail
