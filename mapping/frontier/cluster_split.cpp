#include "mapping/frontier/cluster_split.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "mapping/detail/block_table.h"

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

  void extendBox(const Moments& o) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], o.lo[i]);
      hi[i] = std::max(hi[i], o.hi[i]);
    }
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

// Voxels of one block run (a sub-mask of the run's voxels), with their moments.
template <typename Wide>
struct Chunk {
  uint32_t run = 0;  // index in the runs: the block and its faces
  BlockMask bits{};
  Moments<Wide> m;
};

// The bounding box of a block's voxels `bits` (not empty), in-block coordinates.
void boxOf(const BlockMask& bits, int8_t lo[3], int8_t hi[3]) {
  uint64_t all = 0;  // the yz-pattern of every x slice
  lo[0] = -1;
  for (int x = 0; x < 8; ++x) {
    if (bits[x] == 0) continue;
    if (lo[0] < 0) lo[0] = static_cast<int8_t>(x);
    hi[0] = static_cast<int8_t>(x);
    all |= bits[x];
  }
  // y: the non-zero bytes of `all`; z: the bits of its bytes OR-ed together.
  uint64_t rows = 0;
  for (int y = 0; y < 8; ++y) rows |= static_cast<uint64_t>(((all >> (8 * y)) & 0xFF) != 0) << y;
  uint64_t columns = all | (all >> 32);
  columns |= columns >> 16;
  columns |= columns >> 8;
  columns &= 0xFF;
  lo[1] = static_cast<int8_t>(__builtin_ctzll(rows));
  hi[1] = static_cast<int8_t>(63 - __builtin_clzll(rows));
  lo[2] = static_cast<int8_t>(__builtin_ctzll(columns));
  hi[2] = static_cast<int8_t>(63 - __builtin_clzll(columns));
}

template <typename Wide>
class Splitter {
 public:
  using M = Moments<Wide>;
  using C = Chunk<Wide>;
  static constexpr uint32_t kNone = ~0u;

  Splitter(const std::vector<BlockRun>& runs, const SplitParams& params, const VoxelIndex& ref, uint64_t& next_id,
           std::vector<FrontierCluster>& out)
      : runs_(runs),
        params_(params),
        max_extent_voxels_(params.maxExtentVoxels()),
        ref_(ref),
        next_id_(next_id),
        out_(out) {}

  // Splits the voxels of all runs, one chunk per run to start with.
  void splitAll() {
    std::vector<uint32_t> ids;
    M all;
    for (uint32_t r = 0; r < runs_.size(); ++r) {
      if (runs_[r].moments->n == 0) continue;
      C c;
      c.run = r;
      c.bits = *runs_[r].bits;
      int64_t d[3];
      offset(r, d);
      c.m.mergeRun(*runs_[r].moments, d);
      all.merge(c.m);
      ids.push_back(static_cast<uint32_t>(chunks_.size()));
      chunks_.push_back(c);
    }
    split(ids, all);
  }

 private:
  // Splits the set made of chunks `ids` (moments m) across its main axis until small enough.
  // Chunks wholly on one side of a plane go there whole; only those it cuts are split voxel by
  // voxel.
  void split(std::vector<uint32_t>& ids, const M& m) {
    if (m.n < params_.min_voxels) return;
    int32_t extent_voxels = 0;
    for (int i = 0; i < 3; ++i) extent_voxels = std::max(extent_voxels, m.hi[i] - m.lo[i] + 1);
    if (extent_voxels > max_extent_voxels_ && m.n >= 2) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m.scaledCovariance());
      const Plane plane{m.n, {m.sum[0], m.sum[1], m.sum[2]}, eig.eigenvectors().col(2)};
      std::vector<uint32_t> low, high;
      M a, b_box;
      for (const uint32_t id : ids) {
        const int where = plane.classify(chunks_[id].m);
        if (where < 0) {
          a.merge(chunks_[id].m);
          low.push_back(id);
        } else if (where > 0) {
          b_box.extendBox(chunks_[id].m);
          high.push_back(id);
        } else {
          const auto [ia, ib] = cut(id, plane);
          if (ia != kNone) {
            a.merge(chunks_[ia].m);
            low.push_back(ia);
          }
          if (ib != kNone) {
            b_box.extendBox(chunks_[ib].m);
            high.push_back(ib);
          }
        }
      }
      if (a.n > 0 && a.n < m.n) {
        M b = m;
        b.subtractSums(a);
        std::copy(b_box.lo, b_box.lo + 3, b.lo);
        std::copy(b_box.hi, b_box.hi + 3, b.hi);
        ids = std::vector<uint32_t>();
        split(low, a);
        split(high, b);
        return;
      }
    }
    emit(m);
  }

  // The block's first voxel relative to the reference.
  void offset(uint32_t run, int64_t d[3]) const {
    for (int i = 0; i < 3; ++i) d[i] = int64_t{runs_[run].block[i]} * kBlockSide - ref_[i];
  }

  // Cuts chunk `id` by the plane, voxel by voxel: appends its low side (side() < 0) and the rest
  // as new chunks, returned (kNone where empty).
  std::pair<uint32_t, uint32_t> cut(uint32_t id, const Plane& plane) {
    const C c = chunks_[id];
    const BlockRun& run = runs_[c.run];
    int64_t d[3];
    offset(c.run, d);
    BlockMask low{}, high{};
    for (int x = 0; x < 8; ++x) {
      for (uint64_t rest = c.bits[x]; rest != 0; rest &= rest - 1) {
        const int o = __builtin_ctzll(rest);
        const int32_t r[3] = {static_cast<int32_t>(d[0] + x), static_cast<int32_t>(d[1] + (o >> 3)),
                              static_cast<int32_t>(d[2] + (o & 7))};
        (plane.side(r) < 0.0 ? low : high)[x] |= rest & (~rest + 1);
      }
    }
    C ca, cb;
    ca.run = cb.run = c.run;
    ca.bits = low;
    cb.bits = high;
    ca.m.mergeRun(blockRunMoments(low, *run.faces), d);
    cb.m = c.m;
    cb.m.subtractSums(ca.m);
    std::pair<uint32_t, uint32_t> out(kNone, kNone);
    if (ca.m.n > 0) {
      out.first = static_cast<uint32_t>(chunks_.size());
      chunks_.push_back(ca);
    }
    if (cb.m.n > 0) {
      int8_t lo[3], hi[3];
      boxOf(high, lo, hi);
      for (int i = 0; i < 3; ++i) {
        cb.m.lo[i] = static_cast<int32_t>(d[i] + lo[i]);
        cb.m.hi[i] = static_cast<int32_t>(d[i] + hi[i]);
      }
      out.second = static_cast<uint32_t>(chunks_.size());
      chunks_.push_back(cb);
    }
    return out;
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

  const std::vector<BlockRun>& runs_;
  const SplitParams& params_;
  const int32_t max_extent_voxels_;
  const VoxelIndex ref_;
  uint64_t& next_id_;
  std::vector<FrontierCluster>& out_;
  std::vector<C> chunks_;  // the runs' chunks, then the parts of every cut one
};

// |sums of products| <= n * extent^2; extent < 2^22 and n < 2^32, so Int128 never overflows.
bool sumsFitInt64(int64_t num_voxels, int64_t extent) {
  return static_cast<double>(num_voxels) * static_cast<double>(extent) * static_cast<double>(extent) < 0x1p62;
}

}  // namespace

RunMoments blockRunMoments(const BlockMask& bits, const std::array<uint8_t, kBlockVoxels>& faces) {
  RunMoments m;
  uint64_t dir[2] = {0, 0};  // FaceTable::packed_dir summed
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
  }
  for (int entry = 0; entry < 9; ++entry) m.dir[entry / 3][entry % 3] = field(dir[entry / 5], entry % 5) - m.n;
  if (m.n > 0) boxOf(bits, m.lo, m.hi);
  return m;
}

void splitComponent(const std::vector<BlockRun>& runs, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out) {
  int64_t n = 0;
  for (const BlockRun& run : runs) n += run.moments->n;
  if (n == 0 || n < params.min_voxels) return;
  // Reference: the component's lowest corner, which does not depend on the voxels' order.
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
  if (sumsFitInt64(n, extent)) {
    Splitter<int64_t>(runs, params, ref, next_id, out).splitAll();
  } else {
    Splitter<Int128>(runs, params, ref, next_id, out).splitAll();
  }
}

void splitComponent(const std::vector<FrontierVoxel>& voxels, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out) {
  // One run per block, blocks in ascending packed order.
  std::vector<uint64_t> keys;
  for (const FrontierVoxel& v : voxels) keys.push_back(packIndex(blockOf(v.ijk)));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<BlockMask> bits(keys.size(), BlockMask{});
  std::vector<std::array<uint8_t, kBlockVoxels>> faces(keys.size());
  for (auto& f : faces) f.fill(0);
  for (const FrontierVoxel& v : voxels) {
    const size_t i = std::lower_bound(keys.begin(), keys.end(), packIndex(blockOf(v.ijk))) - keys.begin();
    const int o = offsetInBlock(v.ijk);
    bits[i][o >> 6] |= 1ull << (o & 63);
    faces[i][o] = v.faces;
  }
  std::vector<RunMoments> moments(keys.size());
  std::vector<BlockRun> runs(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    moments[i] = blockRunMoments(bits[i], faces[i]);
    runs[i] = {unpackIndex(keys[i]), &bits[i], &faces[i], &moments[i]};
  }
  splitComponent(runs, params, next_id, out);
}

}  // namespace cenote::mapping::detail
