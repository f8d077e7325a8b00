#include "sim/sim_config.h"

#include <cmath>

#include "common/enum_names.h"
#include "common/error.h"
#include "common/yaml_section.h"

namespace cenote::sim {

std::vector<ConfigError> SimConfig::validate() const {
  ConfigErrors errors("sim");
  errors.check(num_frames >= 1 && num_frames <= 100000, "num_frames", num_frames, "must be in [1, 100000]");
  errors.check(width_px >= 64 && width_px <= 4096, "width_px", width_px, "must be in [64, 4096]");
  errors.check(height_px >= 64 && height_px <= 4096, "height_px", height_px, "must be in [64, 4096]");
  errors.check(rate_hz > 0.0 && rate_hz <= 1000.0, "rate_hz", rate_hz, "must be in (0, 1000]");
  errors.check(groundtruth_rate_hz >= rate_hz && groundtruth_rate_hz <= 10000.0, "groundtruth_rate_hz", groundtruth_rate_hz,
               "must be in [rate_hz, 10000]");
  errors.check(seed >= 0, "seed", seed, "must be >= 0");
  errors.check(baseline_m > 0.0 && baseline_m <= 2.0, "baseline_m", baseline_m, "must be in (0, 2]");
  errors.check(hfov_deg >= 20.0 && hfov_deg <= 150.0, "hfov_deg", hfov_deg, "must be in [20, 150]");
  errors.check(exposure_ratio >= 0.1 && exposure_ratio <= 10.0, "exposure_ratio", exposure_ratio, "must be in [0.1, 10]");
  errors.check(noise_sigma >= 0.0 && noise_sigma <= 50.0, "noise_sigma", noise_sigma, "must be in [0, 50]");
  errors.check(speed_m_s > 0.0 && speed_m_s <= 5.0, "speed_m_s", speed_m_s, "must be in (0, 5]");
  errors.check(turbidity >= 0.0 && turbidity <= 10.0, "turbidity", turbidity, "must be in [0, 10]");
  errors.check(std::abs(k1) <= 1.0, "k1", k1, "must be in [-1, 1]");
  errors.check(std::abs(k2) <= 1.0, "k2", k2, "must be in [-1, 1]");
  errors.check(mesh_spacing_m >= 0.005 && mesh_spacing_m <= 0.5, "mesh_spacing_m", mesh_spacing_m,
               "must be in [0.005, 0.5]");
  errors.check(surface_spacing_m >= 0.002 && surface_spacing_m <= 0.2, "surface_spacing_m", surface_spacing_m,
               "must be in [0.002, 0.2]");
  errors.check(drift_position_m_per_sqrt_s >= 0.0 && drift_position_m_per_sqrt_s <= 1.0, "drift_position_m_per_sqrt_s",
               drift_position_m_per_sqrt_s, "must be in [0, 1]");
  errors.check(drift_yaw_deg_per_sqrt_s >= 0.0 && drift_yaw_deg_per_sqrt_s <= 10.0, "drift_yaw_deg_per_sqrt_s",
               drift_yaw_deg_per_sqrt_s, "must be in [0, 10]");
  errors.check(loop_closure_period_s > 0.0 && std::isfinite(loop_closure_period_s), "loop_closure_period_s",
               loop_closure_period_s, "must be finite and > 0");
  errors.check(loop_closure_residual >= 0.0 && loop_closure_residual <= 1.0, "loop_closure_residual", loop_closure_residual,
               "must be in [0, 1]");
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
