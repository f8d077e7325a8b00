// map_config.h: settings of the occupancy map, its integration, the distance field and the
// frontiers. Units: metres; probabilities in (0, 1). Sensor-model defaults are OctoMap's, so that
// maps of the two are comparable voxel for voxel.
// Threads: a plain value.
#pragma once

#include <string>
#include <vector>

#include "common/config_error.h"
#include "mapping/log_odds.h"

namespace cenote {
class YamlSection;
}

namespace cenote::mapping {

// How a pose correction moves a frame (history/map_history.h): its rays marched again at the new
// pose (the map then equals the map built from scratch with the corrected poses, bit for bit, at
// the cost of a frame's integration and more), or its stored voxel updates resampled rigidly to the
// new pose (history/frame_resample.h: a third of the march's time; within a voxel of the march,
// which keeps 99.8 % agreement with dense depth but 91 % with the simulated cave's 320x240 stereo,
// docs/CORRECTIONS.md).
enum class CorrectionMove { kMarch, kResample };

struct MapConfig {
  double voxel_size_m = 0.05;          // voxel side, in [0.001, 10]; fixed for the life of a map
  double prob_hit = 0.7;               // occupancy probability after one hit from unknown, in (0.5, 1)
  double prob_miss = 0.4;              // ... after one miss (ray passing through), in (0, 0.5)
  double clamp_min = 0.12;             // log-odds clamped to [logit(clamp_min), logit(clamp_max)];
  double clamp_max = 0.97;             //   0 < clamp_min < prob_miss, prob_hit < clamp_max < 1
  double occupied_threshold = 0.5;     // occupied when p >= this; in (clamp_min, clamp_max)
  double max_range_m = 10.0;           // rays longer are carved to this range with no hit; <= 0: unlimited
  int ray_stop_run = 32;               // a ray, marched from its end, stops after this many voxels in a
                                       // row already carved this batch (integration/ray_batch.h): it
                                       // may leave voxels of the ray unknown, never makes free one the
                                       // whole ray does not cross; 0: march whole rays, OctoMap's voxel
                                       // sets; in [0, 1000]
  int publish_blocks = 64;             // blocks written per exclusive lock: readers wait at most for this
  int num_threads = 0;                 // ray marching threads; 0 = OpenMP default. The map is the same
                                       // for any thread count (set union of the rays' voxels)
  double max_distance_m = 2.0;         // distance field: beyond this, distance() reports this, in (0, 100]
  int frontier_min_voxels = 10;        // frontier clusters with fewer voxels are dropped; >= 1
  double frontier_max_extent_m = 2.0;  // larger clusters are split along their main axis (PCA); > 0
  // The frame store behind pose corrections (history/map_history.h), where one is kept (the server;
  // `cenote run --corrections`).
  int history_max_mb = 1024;                                // disk budget; the oldest frames leave beyond it; [1, 1048576]
  std::string history_dir;                                  // its folder; "" = a new one in the system's temp folder
  double history_quantum_m = 0.001;                         // stored points are rounded to this, relative to the camera
                                                            // (and integrated rounded); in (0, voxel_size_m / 4]
  double correction_min_shift_m = 0.001;                    // a corrected frame moves when its camera moves more than
  double correction_min_turn_deg = 0.01;                    //   this or turns more than this; >= 0 each
  double correction_max_gap_s = 0.5;                        // a frame's corrected pose is interpolated between two
                                                            // corrected poses at most this far apart; > 0
  CorrectionMove correction_move = CorrectionMove::kMarch;  // march | resample (see CorrectionMove)

  LogOddsModel logOddsModel() const;
  // Every failed rule, empty when valid.
  std::vector<ConfigError> validate() const;
  // Reads keys of a `map:` section; unknown keys are errors.
  // @throws Error for a value of the wrong type or an unknown correction_move name.
  void read(YamlSection& section);
};

const char* toString(CorrectionMove move);
// @throws Error "map.correction_move = NAME: must be 'march' or 'resample'".
CorrectionMove parseCorrectionMove(const std::string& name);

}  // namespace cenote::mapping
