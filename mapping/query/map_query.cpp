#include "mapping/query/map_query.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.h"
#include "mapping/detail/mask_bits.h"
#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

constexpr double kMaxBoxVoxels = 2147483648.0;
constexpr uint64_t kMaxBoxVoxelCount = uint64_t{1} << 31;

// Voxels of a box counted along each axis, as a double (no overflow).
double boxVoxels(const Aabb& box_m, double voxel_size_m) {
  return ((box_m.max_m - box_m.min_m) / voxel_size_m).array().ceil().prod();
}

void checkSegment(const SegmentQuery& q, size_t i, const OccupancyMap& map) {
  auto fail = [&](const std::string& why) { throw Error("map query: segment " + std::to_string(i) + why); };
  if (!q.start_m.allFinite() || !q.end_m.allFinite() || !std::isfinite(q.radius_m) || q.radius_m < 0.0) {
    fail(" must have finite ends and a finite radius >= 0");
  }
  const Aabb bounds = boundsOf(q);
  if (!withinMapRange(bounds, map)) fail(" reaches beyond " + mapRangeText(map));
  if (q.radius_m > 0.0 && boxVoxels(bounds, map.voxelSize()) > kMaxBoxVoxels) {
    fail(": its capsule's bounding box holds more than 2^31 voxels");
  }
}

// How far from `origin` along the unit vector `dir` the ray stays within the map's range.
double distanceToRangeEdge(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double range) {
  double t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (dir[a] > 0.0) t = std::min(t, (range - origin[a]) / dir[a]);
    if (dir[a] < 0.0) t = std::min(t, (-range - origin[a]) / dir[a]);
  }
  return t;
}

// Segment: the voxels it passes through, in order.
CollisionResult walkSegment(const OccupancyMap::ConstAccessor& acc, const SegmentQuery& q, bool stop_at_unknown) {
  CollisionResult r;
  const double s = acc.map().voxelSize();
  const Eigen::Vector3d dir = q.end_m - q.start_m;
  const double length = dir.norm();
  auto along = [&](const VoxelIndex& ijk) {
    if (length == 0.0) return 0.0;
    return std::clamp((voxelCentre(ijk, s) - q.start_m).dot(dir) / length, 0.0, length);
  };
  walkVoxels(q.start_m, q.end_m, s, true, [&](const VoxelIndex& ijk) {
    const VoxelState state = acc.state(ijk);
    if (state == VoxelState::kOccupied) {
      r.hit = true;
      r.hit_voxel = ijk;
      r.hit_distance_m = along(ijk);
      return false;
    }
    if (state == VoxelState::kUnknown && !r.crossed_unknown) {
      r.crossed_unknown = true;
      r.unknown_distance_m = along(ijk);
      if (stop_at_unknown) {
        r.stopped_at_unknown = true;
        return false;
      }
    }
    return true;
  });
  return r;
}

// Capsule: every voxel whose centre is within radius of the segment, slab by slab along the
// segment's dominant axis; the first occupied / unknown by projection onto the segment.
CollisionResult sweepCapsule(const OccupancyMap::ConstAccessor& acc, const SegmentQuery& q, bool stop_at_unknown) {
  const double s = acc.map().voxelSize();
  const Eigen::Vector3d a = q.start_m, b = q.end_m, d = b - a;
  const double len2 = d.squaredNorm();
  const double length = std::sqrt(len2);
  const double r = q.radius_m, r2 = r * r;
  int axis;
  d.cwiseAbs().maxCoeff(&axis);
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const Eigen::Vector3d lo = a.cwiseMin(b).array() - r, hi = a.cwiseMax(b).array() + r;
  const VoxelIndex vlo = toVoxel(lo, s), vhi = toVoxel(hi, s);
  double best_occ = std::numeric_limits<double>::infinity(), best_unk = best_occ;
  VoxelIndex occ_voxel = VoxelIndex::Zero();
  for (int i = vlo[axis]; i <= vhi[axis]; ++i) {
    // Segment parameters whose point lies within r of this slab's centre plane bound the slab's
    // cross-section.
    const double x = (i + 0.5) * s;
    double t0 = 0.0, t1 = 1.0;
    if (std::fabs(d[axis]) > 1e-12) {
      const double ta = (x - r - a[axis]) / d[axis], tb = (x + r - a[axis]) / d[axis];
      t0 = std::max(0.0, std::min(ta, tb));
      t1 = std::min(1.0, std::max(ta, tb));
      if (t0 > t1) continue;
    }
    const Eigen::Vector3d p0 = a + t0 * d, p1 = a + t1 * d;
    const int ju0 = static_cast<int>(std::floor((std::min(p0[u], p1[u]) - r) / s));
    const int ju1 = static_cast<int>(std::floor((std::max(p0[u], p1[u]) + r) / s));
    const int jv0 = static_cast<int>(std::floor((std::min(p0[v], p1[v]) - r) / s));
    const int jv1 = static_cast<int>(std::floor((std::max(p0[v], p1[v]) + r) / s));
    for (int ju = ju0; ju <= ju1; ++ju) {
      for (int jv = jv0; jv <= jv1; ++jv) {
        VoxelIndex ijk;
        ijk[axis] = i;
        ijk[u] = ju;
        ijk[v] = jv;
        const Eigen::Vector3d c = voxelCentre(ijk, s);
        const double t = len2 > 0.0 ? std::clamp((c - a).dot(d) / len2, 0.0, 1.0) : 0.0;
        if ((a + t * d - c).squaredNorm() > r2) continue;
        const double dist = t * length;
        if (dist >= best_occ && dist >= best_unk) continue;
        const VoxelState state = acc.state(ijk);
        if (state == VoxelState::kOccupied && dist < best_occ) {
          best_occ = dist;
          occ_voxel = ijk;
        } else if (state == VoxelState::kUnknown && dist < best_unk) {
          best_unk = dist;
        }
      }
    }
  }
  CollisionResult result;
  result.crossed_unknown = best_unk < std::numeric_limits<double>::infinity() && best_unk <= best_occ;
  if (result.crossed_unknown) result.unknown_distance_m = best_unk;
  result.stopped_at_unknown = stop_at_unknown && result.crossed_unknown;
  if (best_occ < std::numeric_limits<double>::infinity() && !result.stopped_at_unknown) {
    result.hit = true;
    result.hit_distance_m = best_occ;
    result.hit_voxel = occ_voxel;
  }
  return result;
}

// The budget: the sum of the items' costs, before any is visited.
void checkBudget(const std::vector<uint64_t>& cost, const char* items, const BatchControl& control) {
  uint64_t total = 0;
  for (const uint64_t c : cost) total = c > std::numeric_limits<uint64_t>::max() - total ? UINT64_MAX : total + c;
  if (total > control.max_voxels) {
    throw ResourceExhaustedError("map query: " + std::to_string(cost.size()) + " " + items + " may visit up to " +
                                 std::to_string(total) + " voxels, more than the budget " + control.budget_name + " = " +
                                 std::to_string(control.max_voxels));
  }
}

// Calls answer(accessor, i) for every item, one accessor (one shared lock) per slice of items whose
// costs reach control.slice_voxels; control.between_slices runs between two slices, unlocked.
template <typename Answer>
void runInSlices(const OccupancyMap& map, const std::vector<uint64_t>& cost, const BatchControl& control, Answer&& answer) {
  size_t i = 0;
  while (i < cost.size()) {
    if (i > 0 && control.between_slices) control.between_slices(i);
    const OccupancyMap::ConstAccessor acc = map.constAccessor();
    uint64_t spent = 0;
    do {
      answer(acc, i);
      spent += cost[i];
      ++i;
    } while (i < cost.size() && spent < control.slice_voxels);
  }
}

}  // namespace

double mapRange_m(const OccupancyMap& map) { return mapRange_m(map.voxelSize()); }

bool withinMapRange(const Aabb& box_m, const OccupancyMap& map) {
  return voxelsOfBox(box_m, map.voxelSize(), "map query: box").within_range;
}

std::string mapRangeText(const OccupancyMap& map) { return mapRangeText(map.voxelSize()); }

uint64_t visitBound(const SegmentQuery& q, double s) {
  const VoxelIndex a = toVoxel(q.start_m.cwiseMin(q.end_m).array() - q.radius_m, s);
  const VoxelIndex b = toVoxel(q.start_m.cwiseMax(q.end_m).array() + q.radius_m, s);
  const Eigen::Array3d extent = (b - a).cast<double>().array() + 1.0;
  if (q.radius_m == 0.0) return static_cast<uint64_t>(extent.sum() - 2.0);  // |di| + |dj| + |dk| + 1
  // sweepCapsule: per slab of the dominant axis, the voxels of a rectangle spanning the segment's
  // points within r of the slab's centre plane (a parameter range of 2 r / |d_axis|), grown by r.
  const double box = extent.prod();
  const Eigen::Vector3d d = (q.end_m - q.start_m).cwiseAbs();
  int axis;
  const double da = d.maxCoeff(&axis);
  if (da <= 1e-12) return static_cast<uint64_t>(box);
  double slabs = extent[axis];
  for (const int u : {(axis + 1) % 3, (axis + 2) % 3}) {
    slabs *= std::min(extent[u], std::floor(2.0 * q.radius_m * (1.0 + d[u] / da) / s) + 2.0);
  }
  return static_cast<uint64_t>(std::min(box, slabs));
}

Aabb boundsOf(const SegmentQuery& segment) {
  Aabb box;
  box.min_m = segment.start_m.cwiseMin(segment.end_m).array() - segment.radius_m;
  box.max_m = segment.start_m.cwiseMax(segment.end_m).array() + segment.radius_m;
  return box;
}

std::vector<VoxelQuery> queryVoxels(const OccupancyMap& map, const std::vector<Eigen::Vector3d>& points_m) {
  const size_t n = points_m.size();
  std::vector<VoxelQuery> out(n);
  const double limit = mapRange_m(map);
  // A voxel no map holds stands for points beyond the map's range (voxel_types.h): always unknown.
  const VoxelIndex nowhere = VoxelIndex::Constant(std::numeric_limits<int>::max());
  std::vector<VoxelIndex> ijk(n);
  for (size_t i = 0; i < n; ++i) {
    const bool valid = points_m[i].allFinite() && !(points_m[i].array().abs() > limit).any();
    ijk[i] = valid ? map.toIndex(points_m[i]) : nowhere;
  }
  std::vector<float> l(n);
  std::vector<uint8_t> known(n);
  map.constAccessor().logOdds(ijk, l, known);  // batched: overlapping cache misses
  for (size_t i = 0; i < n; ++i) {
    if (!known[i]) continue;
    out[i].state = map.model().isOccupied(l[i]) ? VoxelState::kOccupied : VoxelState::kFree;
    out[i].probability = probability(l[i]);
  }
  return out;
}

std::vector<BoxCounts> queryBoxes(const OccupancyMap& map, const std::vector<Aabb>& boxes_m, const BatchControl& control) {
  const double s = map.voxelSize();
  std::vector<VoxelBox> voxels(boxes_m.size());
  std::vector<uint64_t> cost(boxes_m.size());
  for (size_t i = 0; i < boxes_m.size(); ++i) {
    const std::string what = "map query: box " + std::to_string(i);
    const BoxVoxels v = voxelsOfBox(boxes_m[i], s, what);
    if (!v.within_range) throw Error(what + " reaches beyond " + mapRangeText(map));
    if (v.count() > kMaxBoxVoxelCount) throw Error(what + " holds more than 2^31 voxels");
    voxels[i] = v.voxels;
    cost[i] = v.count();
  }
  checkBudget(cost, "boxes", control);
  std::vector<BoxCounts> out(boxes_m.size());
  runInSlices(map, cost, control, [&](const OccupancyMap::ConstAccessor& acc, size_t i) {
    if (voxels[i].isEmpty()) return;
    const VoxelIndex lo = voxels[i].min, hi = voxels[i].max;
    BoxCounts& c = out[i];
    BlockView view;
    const BlockIndex blo = blockOf(lo), bhi = blockOf(hi);
    for (int bx = blo.x(); bx <= bhi.x(); ++bx) {
      for (int by = blo.y(); by <= bhi.y(); ++by) {
        for (int bz = blo.z(); bz <= bhi.z(); ++bz) {
          const BlockIndex block(bx, by, bz);
          if (!acc.readBlock(block, view)) continue;
          detail::forEachSetBit(view.known, [&](int o) {
            const VoxelIndex ijk = voxelOfOffset(block, o);
            if ((ijk.array() < lo.array()).any() || (ijk.array() > hi.array()).any()) return;
            if (map.model().isOccupied(view.log_odds[o])) {
              ++c.occupied;
            } else {
              ++c.free;
            }
          });
        }
      }
    }
    c.unknown = cost[i] - c.free - c.occupied;
  });
  return out;
}

namespace {

std::vector<CollisionResult> runSegments(const OccupancyMap& map, const std::vector<SegmentQuery>& segments,
                                         bool stop_at_unknown, const BatchControl& control, const char* items) {
  std::vector<uint64_t> cost(segments.size());
  for (size_t i = 0; i < segments.size(); ++i) {
    checkSegment(segments[i], i, map);
    cost[i] = visitBound(segments[i], map.voxelSize());
  }
  checkBudget(cost, items, control);
  std::vector<CollisionResult> out(segments.size());
  runInSlices(map, cost, control, [&](const OccupancyMap::ConstAccessor& acc, size_t i) {
    out[i] = segments[i].radius_m > 0.0 ? sweepCapsule(acc, segments[i], stop_at_unknown)
                                        : walkSegment(acc, segments[i], stop_at_unknown);
  });
  return out;
}

}  // namespace

std::vector<CollisionResult> checkSegments(const OccupancyMap& map, const std::vector<SegmentQuery>& segments,
                                           bool stop_at_unknown, const BatchControl& control) {
  return runSegments(map, segments, stop_at_unknown, control, "segments");
}

std::vector<CollisionResult> raycast(const OccupancyMap& map, const std::vector<Ray>& rays, double max_range_m,
                                     bool stop_at_unknown, const BatchControl& control) {
  if (!(max_range_m > 0.0) || !std::isfinite(max_range_m)) {
    throw Error("map raycast: max_range_m = " + std::to_string(max_range_m) + ": must be finite and > 0");
  }
  std::vector<SegmentQuery> segments(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const double n = rays[i].direction.norm();
    if (!rays[i].origin_m.allFinite() || !std::isfinite(n) || n == 0.0) {
      throw Error("map raycast: ray " + std::to_string(i) + " needs a finite origin and a finite non-zero direction");
    }
    if (!withinMapRange(Aabb{rays[i].origin_m, rays[i].origin_m}, map)) {
      throw Error("map raycast: ray " + std::to_string(i) + " starts beyond " + mapRangeText(map));
    }
    segments[i].start_m = rays[i].origin_m;
    // Beyond the map's range every voxel is unknown: the ray ends half a voxel before its edge.
    const double edge = distanceToRangeEdge(rays[i].origin_m, rays[i].direction / n, mapRange_m(map)) -
                        0.5 * map.voxelSize();
    segments[i].end_m = rays[i].origin_m + rays[i].direction * (std::clamp(edge, 0.0, max_range_m) / n);
  }
  return runSegments(map, segments, stop_at_unknown, control, "rays");
}

}  // namespace cenote::mapping
