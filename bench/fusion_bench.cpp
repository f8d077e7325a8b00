// fusion_bench: ms/frame of cenote's depth-map fusion beside a plain single-threaded implementation
// of the same rules (tests/support/fusion_reference.h), measured in the same run on the same input.
// Prints a Markdown table for docs/PERFORMANCE.md.
//   fusion_bench [--threads 2] [--repeat 15]
// An unknown flag or a bad value is an error (exit status not 0, the reason on stderr; --help lists the flags).
// Input: the sinusoidal reef of tests/support/synthetic_scene.h ray-cast at 800x600 (the paper's
// image size) from a survey line, with stereo noise (Gaussian in disparity, 7 % gross outliers,
// 5 % holes), for N_f = 3 and N_f = 5.
#include <CLI/CLI.hpp>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "common/median.h"
#include "pipeline/fusion/back_projection.h"
#include "pipeline/fusion/depth_fusion.h"
#include "tests/support/fusion_reference.h"
#include "tests/support/synthetic_scene.h"

using namespace cenote;

namespace {

struct Stages {
  double render_ms = 0.0, fuse_ms = 0.0, points_ms = 0.0;
  double total() const { return render_ms + fuse_ms + points_ms; }
};

// Median of each stage over `repeat` runs after one warm-up run.
Stages medianStages(const std::function<Stages()>& run, int repeat) {
  run();
  std::vector<double> render, fuse, points, total;
  for (int i = 0; i < repeat; ++i) {
    const Stages s = run();
    render.push_back(s.render_ms);
    fuse.push_back(s.fuse_ms);
    points.push_back(s.points_ms);
    total.push_back(s.total());
  }
  // The total is the median of the totals, not the sum of medians.
  Stages m{median(render), median(fuse), median(points)};
  m.points_ms = median(total) - m.render_ms - m.fuse_ms;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 2, repeat = 15;
  CLI::App app{"fusion_bench: cenote's depth-map fusion beside a plain implementation of the same rules"};
  app.add_option("--threads", threads, "threads of cenote's fusion")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--repeat", repeat, "timed runs per row (median)")->capture_default_str()->check(CLI::Range(1, 10000));
  CLI11_PARSE(app, argc, argv);

  const test::TestCamera camera{800, 600, 650.0};
  const test::StereoNoise noise = test::stereoNoiseFor(camera, 0.15);
  const test::Scene scene = test::reefScene();
  constexpr int kMaxViews = 5;
  const auto poses = test::surveyPoses(kMaxViews, 0.12);
  std::vector<pipeline::DepthFrame> frames;
  omp_set_num_threads(2);
  for (int i = 0; i < kMaxViews; ++i) {
    pipeline::DepthFrame frame = test::renderScene(scene, camera, poses[i], 0.1 * i);
    const test::NoisyDepth noisy = test::addStereoNoise(frame.depth, noise, 40 + i);
    frame.depth = noisy.depth;
    frame.confidence = noisy.confidence;
    frames.push_back(frame);
  }

  std::printf("800x600 reef scene with stereo noise; median of %d runs; cenote on %d threads, the plain "
              "implementation on 1\n\n",
              repeat, threads);
  std::printf(
      "| N_f | implementation | threads | render ms | fuse ms | copy + points ms | total ms/frame | plain / this |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (int n_views : {3, 5}) {
    pipeline::FusionConfig config;
    config.num_views = n_views;
    const int first = (kMaxViews - n_views) / 2;
    std::vector<const pipeline::DepthFrame*> window;
    for (int i = 0; i < n_views; ++i) window.push_back(&frames[first + i]);

    omp_set_num_threads(1);
    const Stages plain = medianStages(
        [&] {
          test::ReferenceFusionTimings t;
          test::fuseViewsReference(window, config, &t);
          return Stages{t.render_ms, t.fuse_ms, 0.0};
        },
        std::max(1, repeat / 5));

    auto ours = [&](int n_threads) {
      omp_set_num_threads(n_threads);
      // What FusionWindow::push() does once the window is full, buffers reused from call to call:
      // copy the new frame in, fuse, back-project.
      pipeline::FusionScratch scratch;
      pipeline::DepthFrame fused, slot;
      PointBatch points;
      return medianStages(
          [&] {
            pipeline::FusionTimings t;
            const auto start = std::chrono::steady_clock::now();
            window.back()->depth.copyTo(slot.depth);
            window.back()->confidence.copyTo(slot.confidence);
            window.back()->color.copyTo(slot.color);
            const double copy_ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
            pipeline::fuseViews(window, config, scratch, fused, &t);
            const auto points_start = std::chrono::steady_clock::now();
            pipeline::backProject(fused, points);
            const double points_ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - points_start).count();
            return Stages{t.render_ms, t.fuse_ms, points_ms + copy_ms};
          },
          repeat);
    };
    const Stages one = ours(1);
    const Stages many = ours(threads);
    auto row = [&](const char* name, int n_threads, const Stages& s, bool has_points) {
      std::printf("| %d | %s | %d | %.2f | %.2f | %s | %.2f | %.1fx |\n", n_views, name, n_threads, s.render_ms, s.fuse_ms,
                  has_points ? std::to_string(s.points_ms).substr(0, 4).c_str() : "-", s.total(),
                  plain.total() / s.total());
    };
    row("plain (Eigen double, per-pixel lists)", 1, plain, false);
    row("cenote", 1, one, true);
    row("cenote", threads, many, true);
  }
  std::printf("\n'points' = copying the new frame into the window + back-projection into coloured world points\n"
              "(what FusionWindow::push() adds to rendering and fusion); the plain implementation does neither.\n");
  return 0;
}
