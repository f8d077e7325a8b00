// map_bench: cenote's occupancy map beside OctoMap on the same frames, in the same run.
// Integration: the same ~270k-point frames into OccupancyMap::integrate and into
// octomap::OcTree::insertPointCloud (discretize on, the fast OctoMap mode) at 5 cm with a 10 m
// maximum range; CPU and wall ms/frame (bench/integration_peers.h), ratio and memory of both. Then queries on the resulting maps: single
// voxel lookups per second (one thread), 10 m segment checks, and OctoMap's search() / castRay()
// beside them. Prints a Markdown table for docs/PERFORMANCE.md, and the two maps' voxel sets
// compared voxel by voxel (free here but not in OctoMap: free space no exact ray carved).
//   map_bench [--frames 10] [--threads 2] [--voxel 0.05] [--integrate-only 1] [--updates-only 1]
//             [--distance 0] [--lookups-only 1] [--clears-only 1] [--peers-only 1] [--write-frames DIR]
// At most one of the five modes (--*-only 1); none: the full comparison.
// --peers-only: the integration rows alone, with our map's voxel counts and fingerprint (1 and
// `threads` threads); --write-frames DIR (with it or the full run) also writes the views as depth
// images for bench/open3d_bench.py, which adds Open3D's TSDF integration of them. An unknown flag, a missing or
// bad value, or two modes at once is an error (exit status not 0, the reason on stderr; --help lists the flags).
// --integrate-only: integrates the frames into our map only (for perf / callgrind, run with
// OMP_WAIT_POLICY set: the bench re-executes itself otherwise), prints ms/frame and the map's fingerprint,
// and the rays' DDA steps per frame (RayBatch::numSteps).
// --lookups-only: integrates the frames, then times the same random lookups as the full run, single
// calls and batched alternating, five rounds each (medians, wall and thread CPU time), and says
// where the probes fall (absent block, unknown, free, occupied).
// --clears-only: integrates the frames, then times knownBlocks(), 20 clearBox and 20 clearSphere
// calls (boxes and spheres of 0.5-2 m along the path; process CPU, medians of 5 fresh maps), with a
// fingerprint of every known voxel's state and colour afterwards to compare versions.
// --updates-only: integrates the frames and times only the frontier and distance field updates
// (wall and thread CPU time, medians after the first frame), with a fingerprint of the clusters to
// compare versions, and one of the distance field's answers near the map; --distance 0 leaves the distance field out (profile frontiers alone).
// Frames: an 800x600 camera (fx 600) flying 2 m above a sloping sea floor with rocks, looking
// 14 degrees down (so that a frame has ~270k points), ray-cast exactly with 1 cm depth noise
// (tests/mapping/support/analytic_scene.h);
// pixels that see nothing within 12 m give no point (a stereo hole carves nothing).
#include <CLI/CLI.hpp>
#include <octomap/OcTree.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <utility>
#include <span>
#include <string>
#include <vector>

#include "bench/integration_peers.h"
#include "bench/map_fingerprint.h"
#include "bench/omp_wait_policy.h"
#include "common/cpu_clock.h"
#include "common/median.h"
#include "common/size_format.h"
#include "mapping/distance/distance_field.h"
#include "mapping/frontier/frontier_map.h"
#include "mapping/integration/depth_frame.h"
#include "mapping/integration/ray_batch.h"
#include "mapping/integration/voxel_ray.h"
#include "mapping/occupancy_map.h"
#include "mapping/query/map_query.h"
#include "tests/mapping/support/analytic_scene.h"
#include "tests/mapping/support/voxel_sets.h"

using namespace cenote;
using namespace cenote::mapping;
using cenote::bench::fnvMixBytes;
using cenote::bench::kFnvOffset;
using cenote::bench::kFnvPrime;

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr double kPitch = 0.24;  // radians below the horizon

struct BenchView {
  test::Scene scene;
  PinholeCamera camera;
  std::vector<Eigen::Isometry3d> poses;
};

BenchView benchView(int count) {
  BenchView view;
  test::Scene& scene = view.scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -2.0), Eigen::Vector3d(0.03, 0.05, 1.0).normalized()});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0.0, 14.0), y(-5.0, 5.0), r(0.2, 1.0);
  for (int i = 0; i < 40; ++i) scene.spheres.push_back({Eigen::Vector3d(x(rng), y(rng), -2.0), r(rng)});
  PinholeCamera& camera = view.camera;
  camera.width = 800;
  camera.height = 600;
  camera.fx = camera.fy = 600.0;
  camera.cx = 399.5;
  camera.cy = 299.5;
  for (int f = 0; f < count; ++f) {
    const Eigen::Vector3d position(0.3 * f, 0.05 * f, 0.0);
    const Eigen::Vector3d target = position + Eigen::Vector3d(std::cos(kPitch), 0.0, -std::sin(kPitch));
    view.poses.push_back(test::lookAt(position, target));
  }
  return view;
}

std::vector<PointBatch> makeFrames(const BenchView& view) {
  std::vector<PointBatch> frames;
  for (size_t f = 0; f < view.poses.size(); ++f) {
    frames.push_back(test::renderBatch(view.scene, view.camera, view.poses[f], 12.0, 0.01, 100 + f));
  }
  return frames;
}

// The same views as depth images, for projective integration.
std::vector<DepthFrame> makeDepthFrames(const BenchView& view) {
  std::vector<DepthFrame> frames;
  for (size_t f = 0; f < view.poses.size(); ++f) {
    frames.push_back(test::renderDepth(view.scene, view.camera, view.poses[f], 12.0, 0.01, 100 + f));
  }
  return frames;
}

// The first frame starts from an empty map: left out when there are others.
double medianAfterFirst(std::vector<double> v) {
  if (v.size() > 1) v.erase(v.begin());
  return median(std::move(v));
}
double mean(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); }

// Per-frame times of the incremental frontier and distance field updates, each frame's MapDelta
// given to both right after its integration.
struct UpdateTimes {
  std::vector<double> frontier_ms, frontier_cpu_ms, distance_ms, distance_cpu_ms;
  size_t num_clusters = 0, num_frontier_voxels = 0;
  uint64_t cluster_fingerprint = 0;   // FNV-1a over the clusters' counts, centroids and directions
  uint64_t distance_fingerprint = 0;  // FNV-1a over the field's queries at every voxel centre near the map
};

UpdateTimes timeUpdates(const std::vector<PointBatch>& frames, const MapConfig& config, bool with_distance) {
  UpdateTimes out;
  OccupancyMap live(config);
  FrontierMap frontiers(live);
  DistanceField field(live);
  for (const auto& f : frames) {
    const MapDelta delta = live.integrate(f);
    auto t = Clock::now();
    double c = threadCpuMs();
    frontiers.update(delta);
    out.frontier_ms.push_back(msSince(t));
    out.frontier_cpu_ms.push_back(threadCpuMs() - c);
    if (!with_distance) continue;
    t = Clock::now();
    c = threadCpuMs();
    field.update(delta);
    out.distance_ms.push_back(msSince(t));
    out.distance_cpu_ms.push_back(threadCpuMs() - c);
  }
  const auto clusters = frontiers.clusters(Eigen::Vector3d::Zero());
  out.num_clusters = clusters.size();
  out.num_frontier_voxels = frontiers.numFrontierVoxels();
  uint64_t h = kFnvOffset;
  auto mix = [&h](double v) { fnvMixBytes(h, static_cast<uint64_t>(std::llround(v * 1e6))); };
  for (const auto& c : clusters) {
    mix(static_cast<double>(c.num_voxels));
    for (int i = 0; i < 3; ++i)
      mix(c.centroid_m[i]), mix(c.direction[i]), mix(c.bounds_m.min_m[i]), mix(c.bounds_m.max_m[i]);
  }
  out.cluster_fingerprint = h;
  if (with_distance) out.distance_fingerprint = bench::distanceFingerprint(live, field);
  return out;
}

// Random points inside the map's bounds: the probes of the lookup rows.
std::vector<Eigen::Vector3d> lookupProbes(const MapStats& stats, std::mt19937& rng) {
  std::vector<Eigen::Vector3d> probes(2'000'000);
  for (auto& p : probes) {
    for (int k = 0; k < 3; ++k) {
      p[k] = std::uniform_real_distribution<double>(stats.bounds_m.min_m[k], stats.bounds_m.max_m[k])(rng);
    }
  }
  return probes;
}

struct LookupTimes {
  double per_s = 0.0, cpu_per_s = 0.0;  // lookups per second of wall and of thread CPU time
  size_t occupied_seen = 0;
};

// One call per probe (ConstAccessor::state), toIndex inside the timed loop.
LookupTimes timeSingleLookups(const OccupancyMap& map, const std::vector<Eigen::Vector3d>& probes) {
  LookupTimes out;
  const auto t = Clock::now();
  const double c = threadCpuMs();
  {
    const auto acc = map.constAccessor();
    for (const auto& p : probes) out.occupied_seen += acc.state(map.toIndex(p)) == VoxelState::kOccupied;
  }
  out.cpu_per_s = probes.size() / ((threadCpuMs() - c) / 1000.0);
  out.per_s = probes.size() / (msSince(t) / 1000.0);
  return out;
}

// The same probes through the batched lookup (ConstAccessor::states, as queryVoxels uses it), 4096
// at a time; toIndex inside the timed loop as above.
LookupTimes timeBatchedLookups(const OccupancyMap& map, const std::vector<Eigen::Vector3d>& probes) {
  LookupTimes out;
  const auto t = Clock::now();
  const double c = threadCpuMs();
  {
    const auto acc = map.constAccessor();
    constexpr size_t kBatch = 4096;
    std::vector<VoxelIndex> ijk(kBatch);
    std::vector<VoxelState> states(kBatch);
    for (size_t begin = 0; begin < probes.size(); begin += kBatch) {
      const size_t n = std::min(kBatch, probes.size() - begin);
      for (size_t i = 0; i < n; ++i) ijk[i] = map.toIndex(probes[begin + i]);
      acc.states(std::span<const VoxelIndex>(ijk.data(), n), std::span<VoxelState>(states.data(), n));
      for (size_t i = 0; i < n; ++i) out.occupied_seen += states[i] == VoxelState::kOccupied;
    }
  }
  out.cpu_per_s = probes.size() / ((threadCpuMs() - c) / 1000.0);
  out.per_s = probes.size() / (msSince(t) / 1000.0);
  return out;
}

// --lookups-only: five rounds of single and batched lookups, alternating, on one map.
void reportLookups(const OccupancyMap& map) {
  std::mt19937 rng(5);
  const std::vector<Eigen::Vector3d> probes = lookupProbes(map.stats(), rng);
  std::vector<double> single, single_cpu, batched, batched_cpu;
  for (int round = 0; round < 5; ++round) {
    const LookupTimes s = timeSingleLookups(map, probes), b = timeBatchedLookups(map, probes);
    single.push_back(s.per_s / 1e6), single_cpu.push_back(s.cpu_per_s / 1e6);
    batched.push_back(b.per_s / 1e6), batched_cpu.push_back(b.cpu_per_s / 1e6);
  }
  size_t absent = 0, by_state[3] = {0, 0, 0};
  {
    const auto acc = map.constAccessor();
    BlockView view;
    for (const auto& p : probes) {
      const VoxelIndex ijk = map.toIndex(p);
      absent += !acc.readBlock(blockOf(ijk), view);
      ++by_state[static_cast<int>(acc.state(ijk))];
    }
  }
  std::printf("single voxel lookups: %.1f M/s median wall, %.1f M/s of thread CPU (5 rounds)\n", median(single),
              median(single_cpu));
  std::printf("batched lookups (4096): %.1f M/s median wall, %.1f M/s of thread CPU (5 rounds)\n", median(batched),
              median(batched_cpu));
  const double n = static_cast<double>(probes.size()) / 100.0;
  std::printf("probes: %.1f %% in blocks without known voxels; %.1f %% unknown, %.1f %% free, %.1f %% occupied\n",
              absent / n, by_state[0] / n, by_state[1] / n, by_state[2] / n);
}

// --clears-only: see the header comment.
void reportClears(const std::vector<PointBatch>& frames, const MapConfig& config) {
  std::vector<double> known_ms, box_ms, sphere_ms;
  uint64_t fingerprint = kFnvOffset;
  for (int round = 0; round < 5; ++round) {
    OccupancyMap map(config);
    for (const auto& f : frames) map.integrate(f);
    double c = processCpuMs();
    for (int k = 0; k < 20; ++k) map.constAccessor().knownBlocks();
    known_ms.push_back((processCpuMs() - c) / 20);
    c = processCpuMs();
    for (int k = 0; k < 20; ++k) {
      Aabb box;
      box.min_m = Eigen::Vector3d(2.0 + 0.3 * k, -0.5, -3.0);
      box.max_m = box.min_m + Eigen::Vector3d(0.5, 1.0, 2.0);
      map.clearBox(box);
    }
    box_ms.push_back((processCpuMs() - c) / 20);
    c = processCpuMs();
    for (int k = 0; k < 20; ++k) map.clearSphere(Eigen::Vector3d(1.0 + 0.4 * k, 2.0, -2.0), 0.4);
    sphere_ms.push_back((processCpuMs() - c) / 20);
    if (round > 0) continue;
    const auto acc = map.constAccessor();
    for (const BlockIndex& block : acc.knownBlocks()) {
      for (int offset = 0; offset < kBlockVoxels; ++offset) {
        const VoxelIndex ijk = voxelOfOffset(block, offset);
        std::array<uint8_t, 3> rgb{};
        const bool coloured = acc.color(ijk, rgb);
        const uint64_t v = static_cast<uint64_t>(acc.state(ijk)) | coloured << 2 | rgb[0] << 3 | rgb[1] << 11 |
                           rgb[2] << 19;
        fingerprint = (fingerprint ^ v) * kFnvPrime;  // a voxel's word at once
      }
    }
  }
  std::printf("knownBlocks %.3f ms, clearBox %.3f ms, clearSphere %.3f ms (process CPU, medians of 5 maps); "
              "states and colours after the clears: fingerprint %016llx\n",
              median(known_ms), median(box_ms), median(sphere_ms), static_cast<unsigned long long>(fingerprint));
}

// Voxel-by-voxel comparison of the free and occupied sets of our map and OctoMap's (pruned leaves
// expanded): a voxel free here that OctoMap does not hold free was made free by no exact ray.
struct VoxelSetDiff {
  size_t octo_free = 0, octo_occupied = 0;
  size_t free_not_octo_free = 0, octo_free_not_free = 0;  // extra and missing free voxels
  size_t occupied_differ = 0;                             // occupied in one map only
};

VoxelSetDiff compareVoxelSets(const OccupancyMap& map, const octomap::OcTree& tree) {
  const test::VoxelSets ours = test::voxelSets(map), octo = test::voxelSets(tree, map);
  VoxelSetDiff d;
  d.octo_free = octo.free.size();
  d.octo_occupied = octo.occupied.size();
  d.free_not_octo_free = test::countNotIn(ours.free, octo.free);
  d.octo_free_not_free = test::countNotIn(octo.free, ours.free);
  d.occupied_differ = test::countNotIn(ours.occupied, octo.occupied) + test::countNotIn(octo.occupied, ours.occupied);
  return d;
}

// The command line; see the header comment.
struct Options {
  int num_frames = 10;
  int threads = 2;
  double voxel_m = 0.05;
  bool integrate_only = false, updates_only = false, lookups_only = false, clears_only = false, peers_only = false;
  bool with_distance = true;  // --distance, for --updates-only
  std::string write_frames;   // --write-frames, for --peers-only and the full run
};

constexpr double kMaxRangeM = 10.0;

// The map of every mode: `voxel_m`, a 10 m maximum range, `threads` ray-marching threads.
MapConfig mapConfig(const Options& o, int threads) {
  MapConfig config;
  config.voxel_size_m = o.voxel_m;
  config.max_range_m = kMaxRangeM;
  config.num_threads = threads;
  return config;
}

// Integration, ours, on `threads` threads: the frames into a fresh map after one warm-up frame.
std::unique_ptr<OccupancyMap> integrateOurs(const std::vector<PointBatch>& frames, const Options& o, int threads,
                                            bench::IntegrationTime& time) {
  std::unique_ptr<OccupancyMap> map;
  time = bench::timeOurIntegration(frames, mapConfig(o, threads), map);
  return map;
}

// --clears-only: see the header comment.
void runClearsOnly(const Options& o, const std::vector<PointBatch>& frames) {
  reportClears(frames, mapConfig(o, o.threads));
}

// --updates-only: the frontier and distance field updates alone, with their fingerprints.
void runUpdatesOnly(const Options& o, const std::vector<PointBatch>& frames) {
  const UpdateTimes u = timeUpdates(frames, mapConfig(o, o.threads), o.with_distance);
  std::printf("frontier update: %.2f ms/frame median wall, %.2f ms CPU (mean with the first frame %.2f wall); "
              "%zu clusters, %zu frontier voxels, fingerprint %016llx\n",
              medianAfterFirst(u.frontier_ms), medianAfterFirst(u.frontier_cpu_ms), mean(u.frontier_ms), u.num_clusters,
              u.num_frontier_voxels, static_cast<unsigned long long>(u.cluster_fingerprint));
  if (o.with_distance) {
    std::printf("distance field update: %.2f ms/frame median wall, %.2f ms CPU (mean with the first frame %.2f wall); "
                "fingerprint %016llx\n",
                medianAfterFirst(u.distance_ms), medianAfterFirst(u.distance_cpu_ms), mean(u.distance_ms),
                static_cast<unsigned long long>(u.distance_fingerprint));
  }
}

// --integrate-only: our integration alone (for perf / callgrind), ms/frame of wall and of CPU time,
// and the fingerprint of the map; then, untimed (outside OccupancyMap::integrate, so outside
// callgrind's collection), the rays' DDA steps and the voxels they update, per frame.
void runIntegrateOnly(const Options& o, const std::vector<PointBatch>& frames) {
  bench::IntegrationTime time;
  const auto map = integrateOurs(frames, o, o.threads, time);
  const MapStats stats = map->stats();
  std::printf("integration, %d threads: %.1f ms/frame, %.1f ms/frame CPU of all threads; %llu occupied, %llu free "
              "voxels; map fingerprint %016llx\n",
              o.threads, time.wall_ms, time.cpu_ms, static_cast<unsigned long long>(stats.occupied),
              static_cast<unsigned long long>(stats.free), static_cast<unsigned long long>(bench::mapFingerprint(*map)));
  const MapConfig config = mapConfig(o, o.threads);
  RayBatch rays;
  size_t steps = 0, rays_cast = 0;
  uint64_t updated = 0;
  for (const PointBatch& frame : frames) {
    rays.build(frame, config.voxel_size_m, config.max_range_m, o.threads, config.ray_stop_run);
    steps += rays.numSteps();
    rays_cast += rays.numRays();
    updated += rays.updates().numUpdated();
  }
  const double n = static_cast<double>(frames.size());
  std::printf("per frame: %.0f rays, %.0f DDA steps, %.0f voxels updated (ray_stop_run %d)\n", rays_cast / n, steps / n,
              static_cast<double>(updated) / n, config.ray_stop_run);
}

// --lookups-only: see the header comment.
void runLookupsOnly(const Options& o, const std::vector<PointBatch>& frames) {
  bench::IntegrationTime time;
  reportLookups(*integrateOurs(frames, o, o.threads, time));
}

// The integration rows of the full run and of --peers-only: ours on `threads` threads and on one
// (their maps' fingerprints must agree), projective integration of the same views as depth images,
// OctoMap into `tree`; with --write-frames, the depth images written for bench/open3d_bench.py.
struct IntegrationRows {
  bench::IntegrationTime ours, ours_1t, projective, octo;
  std::unique_ptr<OccupancyMap> map;  // ours, `threads` threads
  uint64_t fingerprint = 0, fingerprint_1t = 0;
  uint64_t projective_free = 0;
};

IntegrationRows timeIntegrations(const Options& o, const BenchView& view, const std::vector<PointBatch>& frames,
                                 octomap::OcTree& tree) {
  IntegrationRows rows;
  rows.fingerprint_1t = bench::mapFingerprint(*integrateOurs(frames, o, 1, rows.ours_1t));
  rows.map = integrateOurs(frames, o, o.threads, rows.ours);
  rows.fingerprint = bench::mapFingerprint(*rows.map);
  const std::vector<DepthFrame> depth_frames = makeDepthFrames(view);
  if (!o.write_frames.empty()) bench::writeDepthFrames(o.write_frames, depth_frames, o.voxel_m, kMaxRangeM);
  std::unique_ptr<OccupancyMap> projected;
  rows.projective = bench::timeProjectiveIntegration(depth_frames, mapConfig(o, o.threads), projected);
  rows.projective_free = projected->stats().free;
  rows.octo = bench::timeOctomapIntegration(frames, kMaxRangeM, tree);
  return rows;
}

// Rows of the Markdown table: CPU time (steadier under load) and wall time, ratio OctoMap / ours.
void printIntegrationRows(const IntegrationRows& r, int threads) {
  auto row = [&](const char* what, const bench::IntegrationTime& ours) {
    std::printf("| %s, CPU ms/frame | %.1f | %.1f | %.1fx |\n", what, ours.cpu_ms, r.octo.cpu_ms,
                r.octo.cpu_ms / ours.cpu_ms);
    std::printf("| %s, wall ms/frame | %.1f | %.1f | %.1fx |\n", what, ours.wall_ms, r.octo.wall_ms,
                r.octo.wall_ms / ours.wall_ms);
  };
  const std::string n = std::to_string(threads);
  row(("integration (" + n + " threads)").c_str(), r.ours);
  row("integration (1 thread)", r.ours_1t);
  row(("projective integration of the same views as depth images (" + n + " threads)").c_str(), r.projective);
}

// --peers-only: the integration rows alone, with the maps' fingerprints.
void runPeersOnly(const Options& o, const BenchView& view, const std::vector<PointBatch>& frames) {
  octomap::OcTree tree(o.voxel_m);
  const IntegrationRows rows = timeIntegrations(o, view, frames, tree);
  std::printf("| measure | cenote | OctoMap | ratio |\n|---|---|---|---|\n");
  printIntegrationRows(rows, o.threads);
  const MapStats stats = rows.map->stats();
  std::printf("\nknown voxels: %llu (%llu occupied, %llu free); map fingerprint %016llx (%d threads), %016llx (1 thread)\n",
              static_cast<unsigned long long>(stats.occupied + stats.free), static_cast<unsigned long long>(stats.occupied),
              static_cast<unsigned long long>(stats.free), static_cast<unsigned long long>(rows.fingerprint), o.threads,
              static_cast<unsigned long long>(rows.fingerprint_1t));
}

// No mode: integration, lookups, segment checks and updates, ours beside OctoMap's, as a Markdown table.
void runFull(const Options& o, const BenchView& view, const std::vector<PointBatch>& frames) {
  const int num_frames = o.num_frames, threads = o.threads;
  const double voxel_m = o.voxel_m, max_range_m = kMaxRangeM;
  const MapConfig live_config = mapConfig(o, threads);
  size_t points = 0;
  for (const auto& f : frames) points += f.size();

  octomap::OcTree tree(voxel_m);
  const IntegrationRows rows = timeIntegrations(o, view, frames, tree);
  const auto& map = rows.map;

  const MapStats stats = map->stats();
  const VoxelSetDiff diff = compareVoxelSets(*map, tree);
  const double ours_mib = stats.memory_bytes / 1048576.0;
  const double octo_mib = tree.memoryUsage() / 1048576.0;

  // Lookups: random voxels inside the map's bounds, one thread.
  std::mt19937 rng(5);
  const std::vector<Eigen::Vector3d> probes = lookupProbes(stats, rng);
  const LookupTimes single_lookups = timeSingleLookups(*map, probes);
  const LookupTimes batched_lookups = timeBatchedLookups(*map, probes);
  const double ours_lookups = single_lookups.per_s, ours_batched_lookups = batched_lookups.per_s;
  const size_t occupied_seen = single_lookups.occupied_seen, occupied_seen_batched = batched_lookups.occupied_seen;
  auto t1 = Clock::now();
  size_t octo_occupied = 0;
  for (const auto& p : probes) {
    const auto* node = tree.search(p.x(), p.y(), p.z());
    octo_occupied += node != nullptr && tree.isNodeOccupied(node);
  }
  const double octo_lookups = probes.size() / (msSince(t1) / 1000.0);

  // 10 m segment checks through the mapped region, from the camera path forwards and down.
  std::vector<SegmentQuery> segments(2000);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  for (auto& s : segments) {
    const Eigen::Vector3d start(std::uniform_real_distribution<double>(0.0, 0.3 * num_frames)(rng), 0.0, 0.0);
    const double yaw = angle(rng), pitch = -0.1 + 0.2 * angle(rng);
    s.start_m = start;
    s.end_m = start +
              10.0 * Eigen::Vector3d(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch));
  }
  // One untimed pass first: both timed passes below then find the map equally warm in cache (the
  // batch ran cold before the single calls, which made it look slower per segment).
  checkSegments(*map, segments, false);
  t1 = Clock::now();
  const auto results = checkSegments(*map, segments, false);
  const double ours_segment_us = msSince(t1) * 1000.0 / segments.size();
  t1 = Clock::now();
  for (const auto& s : segments) checkSegments(*map, {s}, false);
  const double ours_segment_single_us = msSince(t1) * 1000.0 / segments.size();
  size_t octo_hits = 0;
  t1 = Clock::now();
  for (const auto& s : segments) {
    octomap::point3d end;
    const Eigen::Vector3d d = s.end_m - s.start_m;
    octo_hits += tree.castRay(octomap::point3d(s.start_m.x(), s.start_m.y(), s.start_m.z()),
                              octomap::point3d(d.x(), d.y(), d.z()), end, true, 10.0);
  }
  const double octo_segment_us = msSince(t1) * 1000.0 / segments.size();
  size_t ours_hits = 0;
  for (const auto& r : results) ours_hits += r.hit;

  // Incremental distance field and frontiers: update time per frame from each frame's MapDelta
  // (median over the frames after the first, which starts from an empty map; and the mean of all).
  const UpdateTimes updates = timeUpdates(frames, live_config, true);
  const double frontier_ms = medianAfterFirst(updates.frontier_ms), frontier_mean_ms = mean(updates.frontier_ms);
  const double distance_ms = medianAfterFirst(updates.distance_ms), distance_mean_ms = mean(updates.distance_ms);
  const size_t num_clusters = updates.num_clusters;

  std::printf("## Map\n\n");
  std::printf("%d frames of %s points (800x600 camera over a rocky sea floor, 1 cm depth noise), "
              "%.0f cm voxels, %.0f m max range; %d threads; OctoMap %s, insertPointCloud with discretize on.\n\n",
              num_frames, formatCount(static_cast<double>(points) / frames.size()).c_str(), voxel_m * 100, max_range_m,
              threads, "1.9.7");
  std::printf("| measure | cenote | OctoMap | ratio |\n|---|---|---|---|\n");
  printIntegrationRows(rows, threads);
  std::printf("| memory of the map, MiB | %.1f | %.1f | %.2fx |\n", ours_mib, octo_mib, ours_mib / octo_mib);
  std::printf("| single voxel lookups, M/s (1 thread) | %.1f | %.1f | %.1fx |\n", ours_lookups / 1e6, octo_lookups / 1e6,
              ours_lookups / octo_lookups);
  std::printf("| voxel lookups in batches of 4096 (ConstAccessor::states), M/s (1 thread) | %.1f | %.1f | %.1fx |\n",
              ours_batched_lookups / 1e6, octo_lookups / 1e6, ours_batched_lookups / octo_lookups);
  std::printf("| 10 m segment check, us (batch of %zu) | %.2f | %.2f (castRay) | %.1fx |\n", segments.size(),
              ours_segment_us, octo_segment_us, octo_segment_us / ours_segment_us);
  std::printf("| 10 m segment check, us (batch of 1) | %.2f | | |\n", ours_segment_single_us);
  std::printf("| frontier update, ms/frame (incremental; median, mean with the first frame) | %.1f (%.1f) | | |\n",
              frontier_ms, frontier_mean_ms);
  std::printf("| distance field update, ms/frame (incremental, %.1f m max; median, mean) | %.1f (%.1f) | | |\n",
              MapConfig{}.max_distance_m, distance_ms, distance_mean_ms);
  std::printf(
      "\nMap: %llu occupied, %llu free voxels (OctoMap: %zu leaf nodes); segments hitting: %zu ours, %zu OctoMap "
      "castRay (which also stops at unknown: counts differ by design); lookups saw %zu (batched %zu) / %zu occupied; "
      "%zu frontier clusters at the end; projective integration: %llu free voxels.\n",
      static_cast<unsigned long long>(stats.occupied), static_cast<unsigned long long>(stats.free), tree.getNumLeafNodes(),
      ours_hits, octo_hits, occupied_seen, occupied_seen_batched, octo_occupied, num_clusters,
      static_cast<unsigned long long>(rows.projective_free));
  std::printf("Voxel sets against OctoMap's (pruned leaves expanded): OctoMap %zu free, %zu occupied; %zu voxels free "
              "here but not in OctoMap, %zu free in OctoMap but not here, %zu occupied in one map only.\n",
              diff.octo_free, diff.octo_occupied, diff.free_not_octo_free, diff.octo_free_not_free, diff.occupied_differ);
}

}  // namespace

int main(int argc, char** argv) {
  // CPU time is the figure to compare under load; libgomp's idle threads would spin and count.
  bench::sleepingOpenMpWaits(argv, "map_bench");
  Options o;
  CLI::App app{"map_bench: cenote's occupancy map beside OctoMap on the same frames, in the same run"};
  app.add_option("--frames", o.num_frames, "frames of ~270k points")->capture_default_str()->check(CLI::Range(1, 1000));
  app.add_option("--threads", o.threads, "ray-marching threads of our map (0: OpenMP's default)")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  app.add_option("--voxel", o.voxel_m, "voxel size, m")->capture_default_str()->check(CLI::Range(0.001, 10.0));
  app.add_option("--integrate-only", o.integrate_only, "1: time our integration alone");
  app.add_option("--updates-only", o.updates_only, "1: time the frontier and distance field updates alone");
  app.add_option("--distance", o.with_distance, "0: --updates-only without the distance field")->capture_default_str();
  app.add_option("--lookups-only", o.lookups_only, "1: time single and batched lookups alone");
  app.add_option("--clears-only", o.clears_only, "1: time knownBlocks, clearBox and clearSphere alone");
  app.add_option("--peers-only", o.peers_only, "1: the integration rows alone (ours, projective, OctoMap)");
  app.add_option("--write-frames", o.write_frames, "directory: write the frames as depth images (bench/open3d_bench.py)");
  try {
    app.parse(argc, argv);
    if (o.integrate_only + o.updates_only + o.lookups_only + o.clears_only + o.peers_only > 1) {
      throw CLI::ValidationError("--integrate-only, --updates-only, --lookups-only, --clears-only, --peers-only",
                                 "at most one mode at a time");
    }
    if (!o.write_frames.empty() && (o.integrate_only || o.updates_only || o.lookups_only || o.clears_only)) {
      throw CLI::ValidationError("--write-frames", "only with --peers-only 1 or the full run");
    }
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  const BenchView view = benchView(o.num_frames);
  const std::vector<PointBatch> frames = makeFrames(view);
  if (o.clears_only) runClearsOnly(o, frames);
  else if (o.updates_only) runUpdatesOnly(o, frames);
  else if (o.integrate_only) runIntegrateOnly(o, frames);
  else if (o.lookups_only) runLookupsOnly(o, frames);
  else if (o.peers_only) runPeersOnly(o, view, frames);
  else runFull(o, view, frames);
  return 0;
}
