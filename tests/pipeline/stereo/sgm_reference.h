// sgm_reference.h: a plain scalar semi-global matcher that stores the whole cost volume, written
// for clarity, not speed. With one strip the SIMD engine must reproduce it bit for bit, in both
// search modes (SearchMode::kBand: the match of the shrunk pair, then each pixel's band of
// disparities with infinite path costs outside it).
#pragma once

#include "pipeline/frame/frames.h"
#include "pipeline/stereo/stereo_config.h"

namespace cenote::test {

pipeline::DisparityMap referenceSgm(const cv::Mat& left_grey, const cv::Mat& right_grey,
                                    const pipeline::StereoConfig& config);

}  // namespace cenote::test
