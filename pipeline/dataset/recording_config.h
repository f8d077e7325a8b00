// recording_config.h: how `cenote run` reads a recording (the `bag:` section of the configuration):
// which topics hold the stereo images when none are named, and how left and right images are
// paired (pipeline/dataset/stamp_pairing.h).
// Units: seconds. Threads: plain values.
#pragma once

#include <string>
#include <vector>

#include "common/config_error.h"

namespace cenote {
class YamlSection;
}

namespace cenote::pipeline {

// The image topics of a common underwater rig.
struct RigPreset {
  std::string name;  // the key under bag.rigs
  std::string left, right;
};

struct RecordingConfig {
  double sync_tolerance_s = 0.01;  // a left and a right image pair when their stamps differ by at most
                                   // this and each is the other's nearest; >= 0, below half a frame period
  int sync_queue = 64;             // images held waiting for their partner, in [2, 4096]
  int image_bits = 16;             // significant low bits of 16-bit image samples (mono16, bayer_*16, ...),
                                   // in [9, 16]: 12 for a 12-bit camera writing 0..4095
  std::string rig = "auto";        // the preset whose topics are used when --left/--right are not given:
                                   // auto (the first below whose two topics the recording has) or a name
  std::vector<RigPreset> rigs = {
      {"svin2", "/slave1/image_raw/compressed", "/slave2/image_raw/compressed"},
      {"cam_f", "/cam_fl/image_raw/compressed", "/cam_fr/image_raw/compressed"},
      {"left_right", "/left/image_raw", "/right/image_raw"},
  };

  std::vector<ConfigError> validate() const;
  void read(YamlSection& section);
};

}  // namespace cenote::pipeline
