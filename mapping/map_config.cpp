#include "mapping/map_config.h"

#include "common/enum_names.h"
#include "common/yaml_section.h"

namespace cenote::mapping {

LogOddsModel MapConfig::logOddsModel() const {
  LogOddsModel model;
  model.hit = logOdds(prob_hit);
  model.miss = logOdds(prob_miss);
  model.clamp_min = logOdds(clamp_min);
  model.clamp_max = logOdds(clamp_max);
  model.occupied = logOdds(occupied_threshold);
  return model;
}

std::vector<ConfigError> MapConfig::validate() const {
  ConfigErrors errors("map");
  // Written so that NaN fails every rule.
  errors.checkRange("voxel_size_m", voxel_size_m, 0.001, 10.0);
  errors.check(prob_hit > 0.5 && prob_hit < 1.0, "prob_hit", prob_hit, "must be in (0.5, 1)");
  errors.check(prob_miss > 0.0 && prob_miss < 0.5, "prob_miss", prob_miss, "must be in (0, 0.5)");
  errors.check(clamp_min > 0.0 && clamp_min <= prob_miss, "clamp_min", clamp_min, "must be in (0, prob_miss]");
  errors.check(clamp_max < 1.0 && clamp_max >= prob_hit, "clamp_max", clamp_max, "must be in [prob_hit, 1)");
  errors.check(occupied_threshold > clamp_min && occupied_threshold < clamp_max, "occupied_threshold", occupied_threshold,
               "must be in (clamp_min, clamp_max)");
  errors.check(max_range_m <= 1e4 && !(max_range_m != max_range_m), "max_range_m", max_range_m,
               "must be <= 10000 (<= 0: unlimited)");
  errors.checkRange("ray_stop_run", ray_stop_run, 0, 1000);
  errors.checkRange("publish_blocks", publish_blocks, 1, 1 << 20);
  errors.checkRange("num_threads", num_threads, 0, 256);
  errors.check(max_distance_m > 0.0 && max_distance_m <= 100.0, "max_distance_m", max_distance_m, "must be in (0, 100]");
  errors.check(frontier_min_voxels >= 1, "frontier_min_voxels", frontier_min_voxels, "must be >= 1");
  errors.check(frontier_max_extent_m > 0.0, "frontier_max_extent_m", frontier_max_extent_m, "must be > 0");
  errors.checkRange("history_max_mb", history_max_mb, 1, 1 << 20);
  errors.check(history_quantum_m > 0.0 && history_quantum_m <= voxel_size_m / 4, "history_quantum_m", history_quantum_m,
               "must be in (0, voxel_size_m / 4]");
  errors.check(correction_min_shift_m >= 0.0, "correction_min_shift_m", correction_min_shift_m, "must be >= 0");
  errors.check(correction_min_turn_deg >= 0.0, "correction_min_turn_deg", correction_min_turn_deg, "must be >= 0");
  errors.check(correction_max_gap_s > 0.0, "correction_max_gap_s", correction_max_gap_s, "must be > 0");
  return errors.take();
}

void MapConfig::read(YamlSection& section) {
  section.read("voxel_size_m", voxel_size_m);
  section.read("prob_hit", prob_hit);
  section.read("prob_miss", prob_miss);
  section.read("clamp_min", clamp_min);
  section.read("clamp_max", clamp_max);
  section.read("occupied_threshold", occupied_threshold);
  section.read("max_range_m", max_range_m);
  section.read("ray_stop_run", ray_stop_run);
  section.read("publish_blocks", publish_blocks);
  section.read("num_threads", num_threads);
  section.read("max_distance_m", max_distance_m);
  section.read("frontier_min_voxels", frontier_min_voxels);
  section.read("frontier_max_extent_m", frontier_max_extent_m);
  section.read("history_max_mb", history_max_mb);
  section.read("history_dir", history_dir);
  section.read("history_quantum_m", history_quantum_m);
  section.read("correction_min_shift_m", correction_min_shift_m);
  section.read("correction_min_turn_deg", correction_min_turn_deg);
  section.read("correction_max_gap_s", correction_max_gap_s);
  section.readName("correction_move", correction_move, parseCorrectionMove);
}

constexpr EnumName<CorrectionMove> kCorrectionMoveNames[] = {{CorrectionMove::kMarch, "march"},
                                                             {CorrectionMove::kResample, "resample"}};

const char* toString(CorrectionMove move) { return enumName(kCorrectionMoveNames, move); }

CorrectionMove parseCorrectionMove(const std::string& name) {
  return parseEnumName(kCorrectionMoveNames, name, "map.correction_move = " + name, NameQuotes::kSingle);
}

}  // namespace cenote::mapping
