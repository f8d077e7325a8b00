// fusion_reference.h: a plain, single-threaded implementation of the fusion rules of
// pipeline/fusion/depth_fusion.h, written for reading rather than speed (double precision Eigen,
// per-pixel candidate lists, every candidate evaluated in full). Tests compare fuseViews() with it;
// bench/fusion_bench.cpp uses it as the straightforward baseline.
// Units and frames: those of DepthFrame. Threads: none; pure function.
#pragma once

#include <vector>

#include "pipeline/frame/frames.h"
#include "pipeline/fusion/fusion_config.h"

namespace cenote::test {

struct ReferenceFusionTimings {
  double render_ms = 0.0, fuse_ms = 0.0;
};

pipeline::DepthFrame fuseViewsReference(const std::vector<const pipeline::DepthFrame*>& views,
                                        const pipeline::FusionConfig& config, ReferenceFusionTimings* timings = nullptr);

}  // namespace cenote::test
