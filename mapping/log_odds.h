// log_odds.h: the probabilistic sensor model of the occupancy map, in log-odds.
// Units: probabilities in (0, 1); log-odds l = log(p / (1 - p)), natural logarithm (as OctoMap).
// Threads: plain functions and values.
#pragma once

#include <cmath>

namespace cenote::mapping {

inline float logOdds(double probability) { return static_cast<float>(std::log(probability / (1.0 - probability))); }
inline double probability(float log_odds) { return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(log_odds))); }

// The update applied to a voxel, with the clamping bounds, all in log-odds.
// A voxel never observed has log-odds 0 (p = 0.5) before its first update; it is occupied when
// l >= occupied (OctoMap's rule, isNodeOccupied uses >=), free otherwise once observed.
struct LogOddsModel {
  float hit = 0.0f;
  float miss = 0.0f;
  float clamp_min = 0.0f;
  float clamp_max = 0.0f;
  float occupied = 0.0f;

  float applyHit(float l) const { return l + hit > clamp_max ? clamp_max : l + hit; }
  float applyMiss(float l) const { return l + miss < clamp_min ? clamp_min : l + miss; }
  bool isOccupied(float l) const { return l >= occupied; }
};

}  // namespace cenote::mapping
