// sim_bench: speed of the simulator (sim/) per scene, stage by stage, at 800x600.
// Prints a Markdown table for docs/PERFORMANCE.md ("## Simulator").
//   sim_bench [--threads 2] [--frames 20] [--scene cave|reef|wreck|all]
// An unknown flag or a bad value is an error (exit status not 0, the reason on stderr; --help lists the flags).
// Stages of one frame (both cameras): rasterise (visibility + exact depth), radiance (texture,
// light, water), expose (gain, gamma, noise, 8-bit); "frame" is renderFrame() as a whole, measured
// with the threads inside the frame. "dataset" is ms per frame of writeSimDataset (render + PNG +
// PFM on all threads, frames in parallel), the figure that says how long `cenote sim` takes.
#include <CLI/CLI.hpp>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "common/median.h"
#include "sim/image_formation.h"
#include "sim/rasterizer.h"
#include "sim/sim_dataset.h"
#include "sim/simulator.h"

using namespace cenote;
using Clock = std::chrono::steady_clock;

namespace {

double ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

}  // namespace

int main(int argc, char** argv) {
  int threads = 2, frames = 20;
  std::string which = "all";
  CLI::App app{"sim_bench: speed of the simulator per scene, stage by stage, at 800x600"};
  app.add_option("--threads", threads, "OpenMP threads")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--frames", frames, "frames per scene")->capture_default_str()->check(CLI::Range(1, 10000));
  app.add_option("--scene", which, "scene")->capture_default_str()->check(CLI::IsMember({"cave", "reef", "wreck", "all"}));
  CLI11_PARSE(app, argc, argv);
  omp_set_num_threads(threads);
  std::printf(
      "| scene | triangles | scene build ms | rasterise ms | radiance ms | expose ms | frame ms | dataset ms/frame |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const char* name : {"cave", "reef", "wreck"}) {
    if (which != "all" && which != name) continue;
    sim::SimConfig config;
    config.scene = sim::parseSimScene(name);
    config.num_frames = frames;
    const auto t0 = Clock::now();
    const sim::Simulator simulator(config);
    const double build_ms = ms(t0, Clock::now());
    std::vector<double> raster, radiance, expose, frame;
    for (int i = 0; i < frames; ++i) {
      const Eigen::Isometry3d T = simulator.T_world_cam0(simulator.frameTimeS(i));
      const auto a = Clock::now();
      const sim::VisibilityBuffer vis = sim::rasterize(simulator.scene().mesh, simulator.rig().camera, T);
      const auto b = Clock::now();
      const cv::Mat r = sim::renderRadiance(simulator.scene(), simulator.texture(), simulator.rig().camera, T, vis, T);
      const auto c = Clock::now();
      const cv::Mat img = sim::exposeImage(r, simulator.gain(), 2.0f, 1);
      const auto d = Clock::now();
      const sim::SimFrame f = simulator.renderFrame(i);
      const auto e = Clock::now();
      raster.push_back(2 * ms(a, b));
      radiance.push_back(2 * ms(b, c));
      expose.push_back(2 * ms(c, d));
      frame.push_back(ms(d, e));
    }
    const std::string dir = (std::filesystem::temp_directory_path() / ("cenote_sim_bench_" + std::string(name))).string();
    const sim::SimDatasetSummary summary = sim::writeSimDataset(simulator, dir);
    std::filesystem::remove_all(dir);
    std::printf("| %s | %zu | %.0f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", name, simulator.scene().mesh.numTriangles(),
                build_ms, median(raster), median(radiance), median(expose), median(frame),
                1000.0 * summary.wall_s / frames);
    std::fflush(stdout);
  }
  std::printf("\n%d threads, %d frames per scene, 800x600, both cameras; stage figures are medians over frames.\n", threads,
              frames);
  return 0;
}
