// correction_ingest_bench: ingest at 15 Hz while a loop-closure correction runs, against the same
// ingest without one, on the server's map host (server/host/map_host.h: its writer thread, the
// correction in steps between which ingest runs; no gRPC, no stereo pipeline: the batches are
// handed to MapHost::integrateFrame as the server's pipeline hands its fused frames).
// The dive: bench/tunnel_dive.h; --frames of it are integrated through the frame store with the
// drifted poses, the last --moved drifting. Then a client thread submits frames at --hz (the
// dive's next --ring frames, over and over, with later times, none of them covered by the
// correction), first for --baseline-s seconds alone, then while a correction giving every frame
// its true pose runs (MapHost::correctPoses, from another thread, as Ingest.CorrectPoses does).
// A frame is due at start + k / hz and submitted then (or when the previous one returns, if later):
// its latency is from its due time to integrateFrame's return, so waiting behind the correction or
// a late frame counts. Nothing is dropped (integrateFrame blocks; over gRPC StreamFrames pushes
// back the same way): the frames that fall behind show as latency and as a lower rate.
// Prints, with and without the correction: frames submitted, the rate reached, latency p50 / p99 /
// max, integration time (submission to return) p50 / p99, frames later than one period; and the correction's wall and CPU time (whole process, so the
// ingest's CPU is in the second figure).
//   correction_ingest_bench [--frames 1500] [--moved 300] [--width 800] [--height 600]
//                           [--ingest-width W] [--ingest-height H] [--hz 15] [--baseline-s 10]
//                           [--ring 30] [--voxel 0.05] [--threads 2] [--move march|resample]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench/tunnel_dive.h"
#include "common/cpu_clock.h"
#include "common/error.h"
#include "server/host/map_host.h"

namespace {

using namespace cenote;
using Clock = std::chrono::steady_clock;

struct IngestRun {
  std::vector<double> latency_ms;      // from the frame's due time
  std::vector<double> integration_ms;  // from its submission
  double seconds = 0.0;
  double cpu_ms = 0.0;  // the whole process (a correction meanwhile included)
};

// Submits `ring` at `hz` (frame k due at start + k / hz, time stamps from t0_s on) until `stop`
// is set after `min_s` seconds, or until `seconds` when stop is null.
IngestRun ingest(server::MapHost& host, const std::vector<PointBatch>& ring, const std::vector<Eigen::Isometry3d>& poses,
                 double hz, double t0_s, double seconds, const std::atomic<bool>* stop) {
  IngestRun run;
  const Clock::time_point start = Clock::now();
  const double c0 = processCpuMs();
  for (size_t k = 0;; ++k) {
    const Clock::time_point due = start +
                                  std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(k / hz));
    if (stop != nullptr ? stop->load() : (due - start) >= std::chrono::duration<double>(seconds)) break;
    PointBatch batch = ring[k % ring.size()];
    batch.t_s = t0_s + k / hz;
    std::this_thread::sleep_until(due);
    const Clock::time_point submitted = Clock::now();
    host.integrateFrame(batch, poses[k % ring.size()], Eigen::Isometry3d::Identity());
    const Clock::time_point done = Clock::now();
    run.latency_ms.push_back(std::chrono::duration<double, std::milli>(done - due).count());
    run.integration_ms.push_back(std::chrono::duration<double, std::milli>(done - submitted).count());
  }
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  run.cpu_ms = processCpuMs() - c0;
  return run;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5))];
}

void printRow(const char* what, const IngestRun& r, double hz) {
  const auto late = std::count_if(r.latency_ms.begin(), r.latency_ms.end(), [&](double ms) { return ms > 1000.0 / hz; });
  std::printf("| %s | %zu in %.1f s: %.1f Hz | %.0f / %.0f / %.0f ms | %.0f / %.0f ms | %td | %.1f s |\n", what,
              r.latency_ms.size(), r.seconds, r.latency_ms.size() / r.seconds, percentile(r.latency_ms, 0.5),
              percentile(r.latency_ms, 0.99), percentile(r.latency_ms, 1.0), percentile(r.integration_ms, 0.5),
              percentile(r.integration_ms, 0.99), late, r.cpu_ms / 1000.0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("correction_ingest_bench: ingest at 15 Hz during a pose correction, against without one");
  int frames = 1500, moved = 300, width = 800, height = 600, ingest_width = 0, ingest_height = 0, threads = 2, ring = 30;
  double voxel = 0.05, hz = 15.0, baseline_s = 10.0;
  app.add_option("--frames", frames)->check(CLI::Range(2, 100000));
  app.add_option("--moved", moved)->check(CLI::Range(1, 100000));
  app.add_option("--width", width)->check(CLI::Range(16, 4096));
  app.add_option("--height", height)->check(CLI::Range(16, 4096));
  app.add_option("--ingest-width", ingest_width, "frames ingested meanwhile (default: --width)")
      ->check(CLI::Range(16, 4096));
  app.add_option("--ingest-height", ingest_height)->check(CLI::Range(16, 4096));
  app.add_option("--hz", hz)->check(CLI::Range(0.1, 1000.0));
  app.add_option("--baseline-s", baseline_s)->check(CLI::Range(1.0, 3600.0));
  app.add_option("--ring", ring, "distinct frames ingested, over and over")->check(CLI::Range(1, 1000));
  app.add_option("--voxel", voxel)->check(CLI::Range(0.01, 1.0));
  app.add_option("--threads", threads)->check(CLI::Range(1, 256));
  std::string move = "march";
  app.add_option("--move", move, "how a moved frame moves (map.correction_move): march or resample");
  CLI11_PARSE(app, argc, argv);
  mapping::CorrectionMove correction_move;
  try {
    correction_move = mapping::parseCorrectionMove(move);
  } catch (const Error& e) {
    std::fprintf(stderr, "--move: %s\n", e.what());
    return 2;
  }
  if (moved > frames) {
    std::fprintf(stderr, "--moved %d: must be at most --frames %d\n", moved, frames);
    return 2;
  }
  if (ingest_width == 0) ingest_width = width;
  if (ingest_height == 0) ingest_height = height;
  // The ring: the dive's next frames, where the odometry went on drifting; at their true poses
  // (the correction does not cover their times).
  const bench::TunnelDive dive = bench::makeTunnelDive(frames + ring, moved + ring, width, height, 0.3, 2.0);
  const bench::TunnelDive ingest_dive = bench::makeTunnelDive(frames + ring, moved + ring, ingest_width, ingest_height, 0.3,
                                                              2.0);
  std::vector<PointBatch> ring_frames;
  std::vector<Eigen::Isometry3d> ring_poses;
  size_t ring_points = 0;
  for (int i = frames; i < frames + ring; ++i) {
    ring_frames.push_back(bench::tunnelFrame(ingest_dive, i, ingest_dive.truth[i]));
    ring_poses.push_back(ingest_dive.truth[i]);
    ring_points += ring_frames.back().size();
  }

  mapping::MapConfig config;
  config.voxel_size_m = voxel;
  config.num_threads = threads;
  config.history_max_mb = 1 << 16;
  config.correction_move = correction_move;
  server::MapHostOptions options;
  options.frame_history = true;
  server::MapHost host(std::make_unique<mapping::OccupancyMap>(config), options);
  for (int i = 0; i < frames; ++i) {
    host.integrateFrame(bench::tunnelFrame(dive, i, dive.drifted[i]), dive.drifted[i], Eigen::Isometry3d::Identity());
  }
  std::vector<mapping::CorrectedPose> poses = bench::trueTunnelPoses(dive);
  poses.resize(frames);

  const double t_ring_s = (frames + ring) / 15.0;
  const IngestRun alone = ingest(host, ring_frames, ring_poses, hz, t_ring_s, baseline_s, nullptr);

  std::atomic<bool> corrected{false};
  mapping::CorrectionSummary summary;
  double correction_s = 0.0, correction_cpu_ms = 0.0;
  std::thread correction([&] {
    const Clock::time_point t0 = Clock::now();
    const double c0 = processCpuMs();
    summary = host.correctPoses(poses);
    correction_s = std::chrono::duration<double>(Clock::now() - t0).count();
    correction_cpu_ms = processCpuMs() - c0;
    corrected = true;
  });
  const IngestRun during = ingest(host, ring_frames, ring_poses, hz, t_ring_s + baseline_s + 1.0, 0.0, &corrected);
  correction.join();

  std::printf("correction_move: %s; ", move.c_str());
  std::printf("dive: %d frames of %dx%d, %.2f m voxels, %d threads; ingest: %dx%d frames (%.0f points) at %.1f Hz\n",
              frames, width, height, voxel, threads, ingest_width, ingest_height, double(ring_points) / ring, hz);
  std::printf("correction: %zu frames moved, %zu replayed, %zu blocks rebuilt in %.1f s wall, %.1f s CPU of the "
              "process (ingest's included)\n",
              summary.frames_moved, summary.frames_replayed, summary.blocks_rebuilt, correction_s,
              correction_cpu_ms / 1000.0);
  std::printf("| ingest | frames, rate | latency from due p50 / p99 / max | integration p50 / p99 | later than one "
              "period | process CPU |\n");
  std::printf("|---|---|---|---|---|---|\n");
  printRow("alone", alone, hz);
  printRow("during the correction", during, hz);
  return 0;
}
