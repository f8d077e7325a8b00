// fusion_config.h: settings of visibility-based depth-map fusion (fuseViews(), FusionWindow).
// Units: depths and absolute radii in metres; confidences in the units of the input maps (the
// stereo engine's PKRN ratio, >= 1, or any non-negative score); the support radius is either a
// fraction of depth or metres (see SupportRadius).
// Defaults are the paper's (Wang et al., ICRA 2023, Sec. III-D and IV-B): N_f = 3 views,
// eps = 0.04 (relative), C_thres = 0.5.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "common/config_error.h"

namespace cenote {
class YamlSection;
}

namespace cenote::pipeline {

// How eps is turned into a depth tolerance at depth Z: kRelative eps(Z) = eps * Z,
// kAbsolute eps(Z) = eps metres.
enum class SupportRadius { kRelative, kAbsolute };

struct FusionConfig {
  int num_views = 3;  // N_f: views in the window; odd in [3, kMaxViews], the middle one is the reference
  double eps = 0.04;  // support radius: fraction of depth (relative, in (0, 1)) or metres (absolute, > 0)
  SupportRadius support_radius = SupportRadius::kRelative;
  double min_fused_confidence = 0.5;  // C_thres: fused pixels below this are rejected; > 0
  double min_input_confidence = 0.0;  // pre-fusion floor: input pixels below it take no part; >= 0
  double max_depth_m = 4.0;           // input depths beyond it take no part; > 0 (+inf: none). Stereo depth
                                      // error grows as Z^2 / (f b): with f b = 57 px m and 0.2 px of
                                      // disparity error, 4 m is where it reaches 5 cm

  static constexpr int kMaxViews = 15;

  // Every failed rule, empty when valid.
  std::vector<ConfigError> validate() const;
  // Reads keys of a `fusion:` section; unknown keys are errors (the caller's finish()).
  // @throws cenote::Error for a value of the wrong type or an unknown support_radius name.
  void read(YamlSection& section);
};

const char* toString(SupportRadius radius);
// @throws cenote::Error for anything but "relative" or "absolute".
SupportRadius parseSupportRadius(const std::string& name);

}  // namespace cenote::pipeline
