// `cenote sim`: renders a simulated underwater stereo sequence (sim/) and writes it as an
// EuRoC-layout dataset with ground truth (layout in sim/sim_dataset.h).
//   cenote sim --scene cave|reef|wreck --frames N --out DIR [--width 800 --height 600] [--rate 15]
//              [--seed S] [--baseline 0.12] [--exposure-ratio R] [--noise SIGMA] [--drift] [--config FILE]
// Settings: defaults, then the `sim:` section of --config, then the options given here.
#include <omp.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <functional>
#include <string>
#include <vector>

#include "apps/cenote/commands.h"
#include "apps/cenote/progress_bar.h"
#include "apps/cenote/subcommand.h"
#include "common/error.h"
#include "common/yaml_section.h"
#include "sim/sim_dataset.h"
#include "sim/simulator.h"

namespace cenote::apps {
namespace {

struct SimOptions {
  std::string scene, out, config;
  // One per SimConfig option given (--frames, --width, ...): sets its member over what the defaults
  // and --config gave.
  std::vector<std::function<void(sim::SimConfig&)>> overrides;
  bool quiet = false;
  bool drift = false;
};

// Adds the option `name`, which sets `member` of the run's SimConfig.
template <typename T>
void addOverride(CLI::App* cmd, SimOptions* o, const std::string& name, T sim::SimConfig::*member,
                 const std::string& description) {
  cmd->add_option_function<T>(
      name,
      [o, member](const T& value) {
        o->overrides.push_back([member, value](sim::SimConfig& config) { config.*member = value; });
      },
      description);
}

sim::SimConfig makeConfig(const SimOptions& o) {
  sim::SimConfig config;
  if (!o.config.empty()) readConfigFile(o.config, "sim", config);
  if (!o.scene.empty()) {
    try {
      config.scene = sim::parseSimScene(o.scene);
    } catch (const Error&) {
      throw Error("--scene " + o.scene + ": must be cave, reef or wreck");
    }
  }
  for (const auto& set : o.overrides) set(config);
  if (o.drift) config.drift = true;
  throwIfInvalid(config.validate(), "sim");
  return config;
}

void run(const SimOptions& o) {
  const sim::SimConfig config = makeConfig(o);
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (!std::filesystem::is_directory(o.out)) throw Error("--out " + o.out + ": cannot create directory");

  const auto start = std::chrono::steady_clock::now();
  const sim::Simulator simulator(config);
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ProgressBar bar("sim " + std::string(sim::toString(config.scene)));
  const auto total = static_cast<size_t>(config.num_frames);
  const sim::SimDatasetSummary summary = sim::writeSimDataset(simulator, o.out, [&](int done) {
    if (!o.quiet) bar.update(static_cast<size_t>(done), total);
  });
  const PinholeCamera& cam = simulator.rig().camera;
  std::printf("simulated %d frames of the %s scene (%dx%d, f = %.2f px, baseline %.3f m, %zu triangles) into %s\n",
              summary.frames, sim::toString(config.scene), cam.width, cam.height, cam.fx, config.baseline_m,
              simulator.scene().mesh.numTriangles(), o.out.c_str());
  std::printf("ground truth: %zu surface points (%.3f m apart), depth per frame, body and cam0 trajectories\n",
              summary.surface_points, config.surface_spacing_m);
  std::printf("time: scene %.2f s, render %.1f ms/frame, write %.1f ms/frame (per thread), total %.2f s on %d threads\n",
              build_s, summary.render_ms_per_frame, summary.write_ms_per_frame, build_s + summary.wall_s,
              omp_get_max_threads());
}

}  // namespace

void registerSimCommand(CLI::App& app) {
  const auto [cmd, o] = addSubcommand<SimOptions>(
      app, "sim", "Simulate an underwater stereo sequence with ground truth (EuRoC layout)", run);
  cmd->add_option("--scene", o->scene, "cave (tunnel, rig light), reef (lawnmower survey) or wreck (circling a hull)");
  addOverride(cmd, o.get(), "--frames", &sim::SimConfig::num_frames,
              "Number of stereo pairs (sim.num_frames, default 100)");
  cmd->add_option("--out", o->out, "Output folder (EuRoC layout plus groundtruth/)")->required();
  addOverride(cmd, o.get(), "--width", &sim::SimConfig::width_px, "Image width, pixels (default 800)");
  addOverride(cmd, o.get(), "--height", &sim::SimConfig::height_px, "Image height, pixels (default 600)");
  addOverride(cmd, o.get(), "--rate", &sim::SimConfig::rate_hz, "Camera rate, Hz (default 15)");
  addOverride(cmd, o.get(), "--seed", &sim::SimConfig::seed, "Seed of scene shape, texture and noise (default 1)");
  addOverride(cmd, o.get(), "--baseline", &sim::SimConfig::baseline_m, "Stereo baseline, metres (default 0.12)");
  addOverride(cmd, o.get(), "--exposure-ratio", &sim::SimConfig::exposure_ratio,
              "Right camera gain / left camera gain (default 1)");
  addOverride(cmd, o.get(), "--noise", &sim::SimConfig::noise_sigma, "Sensor noise sigma, grey levels (default 2)");
  addOverride(cmd, o.get(), "--speed", &sim::SimConfig::speed_m_s, "Vehicle speed, m/s (default 0.4)");
  addOverride(cmd, o.get(), "--turbidity", &sim::SimConfig::turbidity, "Scales attenuation and backscatter (default 1)");
  addOverride(cmd, o.get(), "--hfov", &sim::SimConfig::hfov_deg, "Horizontal field of view, degrees (default 80)");
  addOverride(cmd, o.get(), "--k1", &sim::SimConfig::k1, "Radial distortion k1 of both cameras (default 0)");
  addOverride(cmd, o.get(), "--k2", &sim::SimConfig::k2, "Radial distortion k2 of both cameras (default 0)");
  cmd->add_option("--config", o->config, "YAML file with a `sim:` section (options given here override it)");
  cmd->add_flag("--drift", o->drift,
                "Also write vio_trajectory.tum (a drifting VIO's live poses) and loop_closures/ (sim.drift)");
  cmd->add_flag("--quiet", o->quiet, "No progress output");
}

}  // namespace cenote::apps
