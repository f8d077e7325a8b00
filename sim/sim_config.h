// sim_config.h: settings of the simulator (`cenote sim`, sim/simulator.h).
// Units: pixels for the image, seconds / hertz for time, metres for lengths, grey levels (0-255)
// for sensor noise. The rig: cam1 is cam0 shifted by baseline_m along cam0's x axis, same
// orientation and intrinsics, so a simulated pair is already rectified (with zero distortion).
// Threads: a plain value.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/config_error.h"

namespace cenote {
class YamlSection;
}

namespace cenote::sim {

enum class SimSceneKind { kCave, kReef, kWreck };

struct SimConfig {
  SimSceneKind scene = SimSceneKind::kCave;
  int num_frames = 100;  // stereo pairs rendered; [1, 100000]
  int width_px = 800;    // image size; [64, 4096] each
  int height_px = 600;
  double rate_hz = 15.0;               // camera rate; (0, 1000]
  double groundtruth_rate_hz = 200.0;  // EuRoC ground-truth rate; >= rate_hz, <= 10000
  int64_t seed = 1;                    // scene shape, texture and sensor noise; >= 0
  double baseline_m = 0.12;            // stereo baseline; (0, 2]
  double hfov_deg = 80.0;              // horizontal field of view (fx = fy); [20, 150]
  double exposure_ratio = 1.0;         // right camera gain / left camera gain; [0.1, 10]
  double noise_sigma = 2.0;            // Gaussian sensor noise, grey levels; [0, 50]
  double speed_m_s = 0.4;              // vehicle speed along the trajectory; (0, 5]
  double turbidity = 1.0;              // scales attenuation and backscatter of the scene's water; [0, 10]
  double k1 = 0.0, k2 = 0.0;           // radial distortion of both cameras (rendered through it); |k| <= 1
  double mesh_spacing_m = 0.04;        // tessellation of curved surfaces; [0.005, 0.5]
  double surface_spacing_m = 0.015;    // point spacing of groundtruth/surface.ply; [0.002, 0.2]
  // A drifting VIO and its loop closures (vio_drift.h): vio_trajectory.tum and loop_closures/.
  bool drift = false;                         // write them (`cenote sim --drift`)
  double drift_position_m_per_sqrt_s = 0.02;  // random walk of the position bias, per axis; [0, 1]
  double drift_yaw_deg_per_sqrt_s = 0.2;      // random walk of the yaw bias; [0, 10]
  double loop_closure_period_s = 10.0;        // a correction event every this many seconds; > 0
  double loop_closure_residual = 0.05;        // fraction of the drift a correction leaves; [0, 1]

  // Every failed rule, empty when valid.
  std::vector<ConfigError> validate() const;
  // Reads keys of a `sim:` section; unknown keys are errors (the caller's finish()).
  // @throws cenote::Error for a value of the wrong type or an unknown scene name.
  void read(YamlSection& section);
};

const char* toString(SimSceneKind scene);
// @throws cenote::Error for anything but "cave", "reef" or "wreck".
SimSceneKind parseSimScene(const std::string& name);

}  // namespace cenote::sim
