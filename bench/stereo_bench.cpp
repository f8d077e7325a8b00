// stereo_bench: ms/frame of cenote's matcher beside OpenCV's StereoSGBM on the same images, in
// the same run, on the same number of threads. Prints a Markdown table for docs/PERFORMANCE.md.
// Besides the wall-clock median it prints the median CPU time per frame (all threads of the
// process): on a machine shared with other work it barely moves when the wall clock doubles.
// It also prints the fastest run ("best ms"), the one least disturbed by other work.
//   stereo_bench [--threads 2] [--repeat 15] [--only-first] [--skip-slow] [--only-default]
// An unknown flag or a bad value is an error (exit status not 0, the reason on stderr; --help lists the flags).
// cenote's rows: the full search and the coarse-to-fine band (StereoConfig::search) of each mode.
// Inputs: Middlebury Cloth3 resized to 800x600 (the paper's image size) with 112 disparities,
// the same stretched to twice its width (its left 800x600: depth edges almost everywhere, the band
// placement's worst case), and the Middlebury pairs at their own size (cones 64, Cloth3 128
// disparities).
#include <CLI/CLI.hpp>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "bench/omp_wait_policy.h"
#include "common/cpu_clock.h"
#include "common/median.h"
#include "pipeline/stereo/stereo_matcher.h"
#include "tests/support/test_data.h"

using namespace cenote;

namespace {

struct Input {
  std::string name;
  cv::Mat left, right;  // grey
  int disparities;
};

struct Timing {
  double wall_ms = 0.0;       // median
  double cpu_ms = 0.0;        // median CPU time of the process (every thread)
  double best_wall_ms = 0.0;  // fastest run: the least disturbed by other work on the machine
};

Timing medianMs(const std::function<void()>& run, int repeat) {
  run();  // warm-up: allocations, page faults
  std::vector<double> wall, cpu;
  for (int i = 0; i < repeat; ++i) {
    const double c0 = processCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    run();
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    cpu.push_back(processCpuMs() - c0);
  }
  return {median(wall), median(cpu), *std::min_element(wall.begin(), wall.end())};
}

cv::Mat grey(const cv::Mat& bgr) {
  cv::Mat g;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  return g;
}

}  // namespace

int main(int argc, char** argv) {
  // OpenCV's threads and ours alike: idle OpenMP threads sleep, so that CPU time measures the work.
  bench::sleepingOpenMpWaits(argv, "stereo_bench");
  int threads = 2, repeat = 15;
  bool only_first = false;    // the 800x600 input alone
  bool skip_slow = false;     // without the 8-path rows and OpenCV's HH4
  bool only_default = false;  // cenote's default settings and OpenCV's 3WAY alone (for profilers)
  CLI::App app{"stereo_bench: cenote's matcher beside OpenCV's StereoSGBM on the same images, in the same run"};
  app.add_option("--threads", threads, "threads of both matchers")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--repeat", repeat, "timed runs per row (median)")->capture_default_str()->check(CLI::Range(1, 10000));
  app.add_flag("--only-first", only_first, "the 800x600 input alone");
  app.add_flag("--skip-slow", skip_slow, "without the 8-path rows and OpenCV's HH4");
  app.add_flag("--only-default", only_default, "cenote's default settings and OpenCV's 3WAY alone (for profilers)");
  CLI11_PARSE(app, argc, argv);
  omp_set_num_threads(threads);
  cv::setNumThreads(threads);

  std::vector<Input> inputs;
  if (auto cloth = test::loadCloth3()) {
    Input big{"Cloth3 resized 800x600", {}, {}, 112};
    cv::resize(grey(cloth->left), big.left, cv::Size(800, 600), 0, 0, cv::INTER_AREA);
    cv::resize(grey(cloth->right), big.right, cv::Size(800, 600), 0, 0, cv::INTER_AREA);
    inputs.push_back(big);
    // A stress case for the band placement: Cloth3 stretched to twice its width, its left 800
    // columns: disparity gradients twice as steep, so that most coarse pixels are at depth edges.
    Input steep{"Cloth3 stretched 1600x600, left 800x600", {}, {}, 112};
    for (auto [image, out] : {std::pair{&cloth->left, &steep.left}, std::pair{&cloth->right, &steep.right}}) {
      cv::Mat wide;
      cv::resize(grey(*image), wide, cv::Size(1600, 600), 0, 0, cv::INTER_AREA);
      *out = wide(cv::Rect(0, 0, 800, 600)).clone();
    }
    inputs.push_back(steep);
    inputs.push_back({"Cloth3 626x555", grey(cloth->left), grey(cloth->right), 128});
  }
  if (auto cones = test::loadCones()) inputs.push_back({"cones 450x375", grey(cones->left), grey(cones->right), 64});
  if (only_first && inputs.size() > 1) inputs.resize(1);
  if (inputs.empty()) {
    // No data beside the project: a textured random pair still measures speed.
    cv::Mat left(600, 800, CV_8U), right;
    cv::randu(left, 0, 255);
    cv::GaussianBlur(left, left, cv::Size(3, 3), 0);
    cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -20, 0, 1, 0);
    cv::warpAffine(left, right, shift, left.size());
    inputs.push_back({"random 800x600", left, right, 112});
  }

  std::printf("threads: %d, median of %d runs, OMP_WAIT_POLICY=%s\n\n", threads, repeat,
              std::getenv("OMP_WAIT_POLICY") ? std::getenv("OMP_WAIT_POLICY") : "(libgomp default)");
  std::printf("| input | disparities | method | ms/frame | Mcells/s | OpenCV 3WAY / this | CPU ms/frame |"
              " 3WAY / this (CPU) | best ms | 3WAY / this (best) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Input& in : inputs) {
    const double cells = static_cast<double>(in.left.total()) * in.disparities;
    struct Row {
      std::string name;
      Timing t;
    };
    std::vector<Row> rows;
    auto ours = [&](const char* name, pipeline::MatchingCost cost, int window, int paths, pipeline::SearchMode search) {
      pipeline::StereoConfig c;
      c.search = search;
      c.num_disparities = in.disparities;
      c.cost = cost;
      c.window_px = window;
      c.num_paths = paths;
      pipeline::StereoMatcher matcher(c);
      rows.push_back({name, medianMs([&] { matcher.match(in.left, in.right); }, repeat)});
    };
    auto opencv = [&](const char* name, int mode) {
      pipeline::StereoConfig c;  // same penalties as ours
      auto sgbm = cv::StereoSGBM::create(0, in.disparities, 3, c.effectiveP1(), c.effectiveP2(), -1, 0, 0, 0, 0, mode);
      cv::Mat out;
      rows.push_back({name, medianMs([&] { sgbm->compute(in.left, in.right, out); }, repeat)});
    };
    using pipeline::MatchingCost;
    using pipeline::SearchMode;
    if (!only_default) ours("cenote SAD 3x3, 4 paths, full search", MatchingCost::kSad, 3, 4, SearchMode::kFull);
    ours("cenote SAD 3x3, 4 paths, band", MatchingCost::kSad, 3, 4, SearchMode::kBand);
    if (!only_default) {
      ours("cenote census 5x5, 4 paths, full search", MatchingCost::kCensus, 5, 4, SearchMode::kFull);
      ours("cenote census 5x5, 4 paths, band", MatchingCost::kCensus, 5, 4, SearchMode::kBand);
    }
    if (!skip_slow && !only_default) {
      ours("cenote SAD 3x3, 8 paths, full search", MatchingCost::kSad, 3, 8, SearchMode::kFull);
      ours("cenote SAD 3x3, 8 paths, band", MatchingCost::kSad, 3, 8, SearchMode::kBand);
      opencv("OpenCV StereoSGBM MODE_HH4", cv::StereoSGBM::MODE_HH4);
    }
    opencv("OpenCV StereoSGBM MODE_SGBM_3WAY", cv::StereoSGBM::MODE_SGBM_3WAY);
    const Timing three_way = rows.back().t;
    for (const Row& r : rows) {
      std::printf("| %s | %d | %s | %.1f | %.0f | %.2fx | %.1f | %.2fx | %.1f | %.2fx |\n", in.name.c_str(), in.disparities,
                  r.name.c_str(), r.t.wall_ms, cells / (r.t.wall_ms * 1e3), three_way.wall_ms / r.t.wall_ms, r.t.cpu_ms,
                  three_way.cpu_ms / r.t.cpu_ms, r.t.best_wall_ms, three_way.best_wall_ms / r.t.best_wall_ms);
    }
  }
  return 0;
}
