// correction_bench: a loop-closure correction (mapping/history/map_history.h) in both of its modes
// (map.correction_move: resample, march) beside the peer's answer to the same correction,
// rebuilding the map from scratch with the corrected poses, in the same run on the same frames.
// The dive: bench/tunnel_dive.h, the odometry drifting over the last --moved frames (growing to
// --drift metres along x and y and --drift-deg of yaw); the correction gives every frame its true
// pose, so exactly those frames move. Each mode corrects a live map of its own (both integrated
// from the same frames, each through a frame store of its own).
// Prints: ms per frame of integration with the frame store and without it, the store's bytes per
// frame, each mode's correction time (and per moved frame; its moves and its replay apart), the
// from-scratch rebuild's time and the ratios, and how far each corrected map agrees with the
// rebuilt one (voxel states; the rebuilt map's occupied voxels each makes free or leaves unknown;
// its occupied voxels within a voxel of a true surface).
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
#include "tests/mapping/support/map_agreement.h"

namespace {

using namespace cenote;
using namespace cenote::mapping;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// One mode's correction, in its steps (as correct() and the server step through them), timed.
struct TimedCorrection {
  double moves_ms = 0.0, moves_cpu = 0.0, total_ms = 0.0, total_cpu = 0.0;
  CorrectionSummary summary;
};

TimedCorrection timeCorrection(MapHistory& history, const std::vector<CorrectedPose>& poses) {
  TimedCorrection t;
  const auto t0 = Clock::now();
  const double c0 = processCpuMs();
  CorrectionPlan plan = history.planCorrection(poses);
  const size_t step = history.movesAtOnce();
  for (size_t i = 0; i < plan.moved.size(); i += step) history.moveFrames(plan, i, i + step);
  t.moves_ms = msSince(t0);
  t.moves_cpu = processCpuMs() - c0;
  t.summary = history.finishCorrection(plan);
  t.total_ms = msSince(t0);
  t.total_cpu = processCpuMs() - c0;
  return t;
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

  // The live maps, one per mode: every frame through a frame store, with the drifted poses.
  MapConfig resample_config = config, march_config = config;
  resample_config.correction_move = CorrectionMove::kResample;
  march_config.correction_move = CorrectionMove::kMarch;
  OccupancyMap live_resample(resample_config), live_march(march_config);
  MapHistory history_resample(live_resample), history_march(live_march);
  double with_store_ms = 0.0, with_store_cpu = 0.0;
  size_t points = 0;
  for (int i = 0; i < frames; ++i) {
    const PointBatch batch = bench::tunnelFrame(dive, i, dive.drifted[i]);
    points += batch.size();
    const auto t0 = Clock::now();
    const double c0 = processCpuMs();
    history_march.integrate(batch, dive.drifted[i]);
    with_store_ms += msSince(t0);
    with_store_cpu += processCpuMs() - c0;
    history_resample.integrate(batch, dive.drifted[i]);
  }
  // The peer: the map rebuilt from scratch with the corrected poses (no store); the drifted live
  // map's agreement with it before the correction.
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
  const test::MapAgreement drifted_agreement = test::compareStates(live_march, rebuilt);
  const std::vector<CorrectedPose> poses = bench::trueTunnelPoses(dive);
  const TimedCorrection march = timeCorrection(history_march, poses);
  const TimedCorrection resample = timeCorrection(history_resample, poses);

  const test::MapAgreement march_agreement = test::compareStates(live_march, rebuilt);
  const test::MapAgreement resample_agreement = test::compareStates(live_resample, rebuilt);

  std::printf("dive: %d frames of %dx%d (%.0f points a frame), %.2f m voxels, %d threads; %zu frames moved\n", frames,
              width, height, double(points) / frames, voxel, threads, march.summary.frames_moved);
  std::printf("| | correction, resample | correction, march | rebuild from scratch (peer) | ratio: resample, march |\n"
              "|---|---|---|---|---|\n");
  const auto per_moved = [](const TimedCorrection& t) { return 1.0 / std::max<size_t>(t.summary.frames_moved, 1); };
  std::printf("| wall time | %.0f ms (%.1f ms per moved frame) | %.0f ms (%.1f ms per moved frame) | %.0f ms | %.3f, "
              "%.3f |\n",
              resample.total_ms, resample.total_ms * per_moved(resample), march.total_ms, march.total_ms * per_moved(march),
              rebuild_ms, resample.total_ms / rebuild_ms, march.total_ms / rebuild_ms);
  std::printf("| CPU time | %.0f ms (%.1f ms per moved frame) | %.0f ms (%.1f ms per moved frame) | %.0f ms | **%.3f**, "
              "%.3f |\n",
              resample.total_cpu, resample.total_cpu * per_moved(resample), march.total_cpu,
              march.total_cpu * per_moved(march), rebuild_cpu, resample.total_cpu / rebuild_cpu,
              march.total_cpu / rebuild_cpu);
  std::printf("| CPU time of the moved frames' integration alone | | | %.0f ms | %.3f, %.3f |\n", rebuild_moved_cpu,
              resample.total_cpu / rebuild_moved_cpu, march.total_cpu / rebuild_moved_cpu);
  const auto steps = [&](const TimedCorrection& t) {
    std::printf("%.0f + %.0f ms wall, %.0f + %.0f ms CPU (%.3f + %.3f of the rebuild)", t.moves_ms, t.total_ms - t.moves_ms,
                t.moves_cpu, t.total_cpu - t.moves_cpu, t.moves_cpu / rebuild_cpu,
                (t.total_cpu - t.moves_cpu) / rebuild_cpu);
  };
  std::printf("| the correction's steps: the moved frames' moves, the replay | ");
  steps(resample);
  std::printf(" | ");
  steps(march);
  std::printf(" | | |\n");
  const auto work = [](const TimedCorrection& t) {
    std::printf("%zu frames moved, %zu replayed, %zu blocks rebuilt", t.summary.frames_moved, t.summary.frames_replayed,
                t.summary.blocks_rebuilt);
  };
  std::printf("| work | ");
  work(resample);
  std::printf(" | ");
  work(march);
  std::printf(" | %d frames marched | |\n", frames);
  const auto agreement = [&](const test::MapAgreement& a) {
    std::printf("%.4f; of its %llu occupied voxels %llu free (%.5f), %llu unknown", a.agreement(),
                static_cast<unsigned long long>(a.reference_occupied),
                static_cast<unsigned long long>(a.occupied_made_free), a.madeFree(),
                static_cast<unsigned long long>(a.occupied_made_unknown));
  };
  std::printf("| agreement with the rebuilt map (voxel states) | ");
  agreement(resample_agreement);
  std::printf(" | ");
  agreement(march_agreement);
  std::printf(" | 1 | |\n");
  std::printf("| occupied voxels within a voxel of a true surface | %.4f | %.4f | %.4f | |\n",
              test::occupiedNearSurfaces(live_resample, dive.scene, voxel),
              test::occupiedNearSurfaces(live_march, dive.scene, voxel),
              test::occupiedNearSurfaces(rebuilt, dive.scene, voxel));
  std::printf("uncorrected (drifted) map against the rebuilt one: %.4f\n", drifted_agreement.agreement());
  std::printf("integration per frame: %.1f ms wall / %.1f ms CPU with the frame store, %.1f / %.1f without; store %.0f "
              "kB per frame (%.1f MB); the resample mode's store, which keeps its moved frames' marched updates too: "
              "%.1f MB\n",
              with_store_ms / frames, with_store_cpu / frames, rebuild_ms / frames, rebuild_cpu / frames,
              history_march.storeBytes() / 1024.0 / history_march.numFrames(), history_march.storeBytes() / 1048576.0,
              history_resample.storeBytes() / 1048576.0);
  std::printf("(points rounded to %.0f mm in the store)\n", config.history_quantum_m * 1000);
  return 0;
}
