#include "sim/sim_config.h"

#include <cmath>

#include "common/enum_names.h"
#include "common/error.h"
#include "common/yaml_section.h"

namespace cenote::sim {

std::vector<ConfigError> SimConfig::validate() const {
  ConfigErrors errors("sim");
  errors.checkRange("num_frames", num_frames, 1, 100000);
  errors.checkRange("width_px", width_px, 64, 4096);
  errors.checkRange("height_px", height_px, 64, 4096);
  errors.check(rate_hz > 0.0 && rate_hz <= 1000.0, "rate_hz", rate_hz, "must be in (0, 1000]");
  errors.check(groundtruth_rate_hz >= rate_hz && groundtruth_rate_hz <= 10000.0, "groundtruth_rate_hz", groundtruth_rate_hz,
               "must be in [rate_hz, 10000]");
  errors.check(seed >= 0, "seed", seed, "must be >= 0");
  errors.check(baseline_m > 0.0 && baseline_m <= 2.0, "baseline_m", baseline_m, "must be in (0, 2]");
  errors.checkRange("hfov_deg", hfov_deg, 20.0, 150.0);
  errors.checkRange("exposure_ratio", exposure_ratio, 0.1, 10.0);
  errors.checkRange("noise_sigma", noise_sigma, 0.0, 50.0);
  errors.check(speed_m_s > 0.0 && speed_m_s <= 5.0, "speed_m_s", speed_m_s, "must be in (0, 5]");
  errors.checkRange("turbidity", turbidity, 0.0, 10.0);
  errors.checkRange("k1", k1, -1.0, 1.0);
  errors.checkRange("k2", k2, -1.0, 1.0);
  errors.checkRange("mesh_spacing_m", mesh_spacing_m, 0.005, 0.5);
  errors.checkRange("surface_spacing_m", surface_spacing_m, 0.002, 0.2);
  errors.checkRange("drift_position_m_per_sqrt_s", drift_position_m_per_sqrt_s, 0.0, 1.0);
  errors.checkRange("drift_yaw_deg_per_sqrt_s", drift_yaw_deg_per_sqrt_s, 0.0, 10.0);
  errors.check(loop_closure_period_s > 0.0 && std::isfinite(loop_closure_period_s), "loop_closure_period_s",
               loop_closure_period_s, "must be finite and > 0");
  errors.checkRange("loop_closure_residual", loop_closure_residual, 0.0, 1.0);
  return errors.take();
}

void SimConfig::read(YamlSection& section) {
  section.readName("scene", scene, parseSimScene);
  section.read("num_frames", num_frames);
  section.read("width_px", width_px);
  section.read("height_px", height_px);
  section.read("rate_hz", rate_hz);
  section.read("groundtruth_rate_hz", groundtruth_rate_hz);
  section.read("seed", seed);
  section.read("baseline_m", baseline_m);
  section.read("hfov_deg", hfov_deg);
  section.read("exposure_ratio", exposure_ratio);
  section.read("noise_sigma", noise_sigma);
  section.read("speed_m_s", speed_m_s);
  section.read("turbidity", turbidity);
  section.read("k1", k1);
  section.read("k2", k2);
  section.read("mesh_spacing_m", mesh_spacing_m);
  section.read("surface_spacing_m", surface_spacing_m);
  section.read("drift", drift);
  section.read("drift_position_m_per_sqrt_s", drift_position_m_per_sqrt_s);
  section.read("drift_yaw_deg_per_sqrt_s", drift_yaw_deg_per_sqrt_s);
  section.read("loop_closure_period_s", loop_closure_period_s);
  section.read("loop_closure_residual", loop_closure_residual);
}

constexpr EnumName<SimSceneKind> kSceneNames[] = {
    {SimSceneKind::kCave, "cave"}, {SimSceneKind::kReef, "reef"}, {SimSceneKind::kWreck, "wreck"}};

const char* toString(SimSceneKind scene) { return enumName(kSceneNames, scene); }

SimSceneKind parseSimScene(const std::string& name) {
  return parseEnumName(kSceneNames, name, "sim.scene = " + name, NameQuotes::kSingle);
}

}  // namespace cenote::sim
