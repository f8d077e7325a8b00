// correction_bench: a loop-closure correction (mapping/history/map_history.h) beside the peer's
// answer to the same correction, rebuilding the map from scratch with the corrected poses, in the
// same run on the same frames.
// The dive: bench/tunnel_dive.h, the odometry drifting over the last --moved frames (growing to
// --drift metres along x and y and --drift-deg of yaw); the correction gives every frame its true
// pose, so exactly those frames move.
// Prints: ms per frame of integration with the frame store and without it, the store's bytes per
// frame, the correction's time (and per moved frame), the from-scratch rebuild's time and the
// ratio, and how far the corrected map agrees with the rebuilt one (voxel states).
//   correction_bench [--frames 1500] [--moved 300] [--width 800] [--height 600] [--voxel 0.05]
//                    [--threads 2] [--drift 0.3] [--drift-deg 2]
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "bench/tunnel_dive.h"
#include "common/cpu_clock.h"
#include "mapping/history/map_history.h"
#include "mapping/occupancy_map.h"
#include "tests/mapping/support/known_blocks.h"

namespace {

using namespace cenote;
using namespace cenote::mapping;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

double stateAgreement(const OccupancyMap& a, const OccupancyMap& b) {
  auto acc_a = a.constAccessor();
  auto acc_b = b.constAccessor();
  const std::vector<BlockIndex> blocks = test::blocksKnownInEither(acc_a, acc_b);
  uint64_t known = 0, same = 0;
  for (const BlockIndex& block : blocks) {
    std::array<uint64_t, 8> ka, oa, kb, ob;
    acc_a.readBlockMasks(block, ka, oa);
    acc_b.readBlockMasks(block, kb, ob);
    for (int w = 0; w < 8; ++w) {
      const uint64_t either = ka[w] | kb[w];
      known += __builtin_popcountll(either);
      same += __builtin_popcountll(either & ~(ka[w] ^ kb[w]) & ~(oa[w] ^ ob[w]));
    }
  }
  return known == 0 ? 1.0 : double(same) / known;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("correction_bench: a pose correction beside a from-scratch rebuild");
  int frames = 1500, moved = 300, width = 800, height = 600, threads = 2;
  double voxel = 0.05, drift_m = 0.3, drift_deg = 2.0;
  app.add_option("--frames", frames)->check(CLI::Range(2, 100000));
  app.add_option("--moved", moved)->check(CLI::Range(1, 100000));
  app.add_option("--width", width)->check(CLI::Range(16, 4096));
  app.add_option("--height", height)->check(CLI::Range(16, 4096));
  app.add_option("--voxel", voxel)->check(CLI::Range(0.01, 1.0));
  app.add_option("--threads", threads)->check(CLI::Range(1, 256));
  app.add_option("--drift", drift_m);
  app.add_option("--drift-deg", drift_deg);
  CLI11_PARSE(app, argc, argv);
  if (moved > frames) {
    std::fprintf(stderr, "--moved %d: must be at most --frames %d\n", moved, frames);
    return 2;
  }
  const bench::TunnelDive dive = bench::makeTunnelDive(frames, moved, width, height, drift_m, drift_deg);
  MapConfig config;
  config.voxel_size_m = voxel;
  config.num_threads = threads;
  config.history_max_mb = 1 << 16;

  // The live map: every frame through the frame store, with the drifted poses.
  OccupancyMap live(config);
  MapHistory history(live);
  double with_store_ms = 0.0, with_store_cpu = 0.0;
  size_t points = 0;
  for (int i = 0; i < frames; ++i) {
    const PointBatch batch = bench::tunnelFrame(dive, i, dive.drifted[i]);
    points += batch.size();
    const auto t0 = Clock::now();
    const double c0 = processCpuMs();
    history.integrate(batch, dive.drifted[i]);
    with_store_ms += msSince(t0);
    with_store_cpu += processCpuMs() - c0;
  }
  const std::vector<CorrectedPose> poses = bench::trueTunnelPoses(dive);
  // correct() in its steps, to time the moved frames' ray marches apart from the replay.
  const auto t0 = Clock::now();
  const double c0 = processCpuMs();
  CorrectionPlan plan = history.planCorrection(poses);
  const size_t step = history.movesAtOnce();  // as correct() and the server step through them
  for (size_t i = 0; i < plan.moved.size(); i += step) history.moveFrames(plan, i, i + step);
  const double march_ms = msSince(t0), march_cpu = processCpuMs() - c0;
  const CorrectionSummary summary = history.finishCorrection(plan);
  const double correction_ms = msSince(t0), correction_cpu = processCpuMs() - c0;

  // The peer: the map rebuilt from scratch with the corrected poses (no store).
  OccupancyMap rebuilt(config);
  double rebuild_ms = 0.0, rebuild_cpu = 0.0, rebuild_moved_cpu = 0.0;
  for (int i = 0; i < frames; ++i) {
    const PointBatch batch = bench::tunnelFrame(dive, i, dive.truth[i]);
    const auto t1 = Clock::now();
    const double c1 = processCpuMs();
    rebuilt.integrate(batch);
    rebuild_ms += msSince(t1);
    rebuild_cpu += processCpuMs() - c1;
    if (i >= frames - moved) rebuild_moved_cpu += processCpuMs() - c1;
  }
  const double agreement = stateAgreement(live, rebuilt);

  std::printf("dive: %d frames of %dx%d (%.0f points a frame), %.2f m voxels, %d threads; %zu frames moved\n", frames,
              width, height, double(points) / frames, voxel, threads, summary.frames_moved);
  std::printf("| | cenote correction | rebuild from scratch (peer) | ratio |\n|---|---|---|---|\n");
  const double per_moved = 1.0 / std::max<size_t>(summary.frames_moved, 1);
  std::printf("| wall time | %.0f ms (%.1f ms per moved frame) | %.0f ms | %.3f |\n", correction_ms,
              correction_ms * per_moved, rebuild_ms, correction_ms / rebuild_ms);
  std::printf("| CPU time | %.0f ms (%.1f ms per moved frame) | %.0f ms | %.3f |\n", correction_cpu,
              correction_cpu * per_moved, rebuild_cpu, correction_cpu / rebuild_cpu);
  std::printf("| CPU time of the moved frames' integration alone | | %.0f ms | %.3f |\n", rebuild_moved_cpu,
              correction_cpu / rebuild_moved_cpu);
  std::printf("| the correction's steps: the moved frames' marches, the replay | %.0f + %.0f ms wall, %.0f + %.0f ms CPU | "
              "| %.3f + %.3f (CPU) |\n",
              march_ms, correction_ms - march_ms, march_cpu, correction_cpu - march_cpu, march_cpu / rebuild_cpu,
              (correction_cpu - march_cpu) / rebuild_cpu);
  std::printf("| work | %zu frames marched, %zu replayed, %zu blocks rebuilt | %d frames marched | |\n",
              summary.frames_moved, summary.frames_replayed, summary.blocks_rebuilt, frames);
  std::printf("integration per frame: %.1f ms wall / %.1f ms CPU with the frame store, %.1f / %.1f without; store %.0f "
              "kB per frame (%.1f MB)\n",
              with_store_ms / frames, with_store_cpu / frames, rebuild_ms / frames, rebuild_cpu / frames,
              history.storeBytes() / 1024.0 / history.numFrames(), history.storeBytes() / 1048576.0);
  std::printf("corrected map against the rebuilt one: %.4f of the known voxels in the same state (points rounded to "
              "%.0f mm in the store)\n",
              agreement, config.history_quantum_m * 1000);
  return 0;
}
