// stereo_matcher.h: dense disparity of a rectified pair by semi-global matching.
//
//   cost:        SAD over a w x w window (the paper's), or census w x w with Hamming distance
//                (robust to exposure differences between the cameras)
//   aggregation: 4 paths in one top-down pass (rSGM, Spangenberg et al. 2014) or 8 paths in two
//   disparity:   winner-take-all, parabola through the aggregated costs at d-1, d, d+1
//   confidence:  PKRN = (c2 + 1) / (c1 + 1), c1 the smallest aggregated cost and c2 the second
//                smallest; c2 is taken outside d*-1..d*+1 by default, since the naive second
//                smallest is nearly always the winner's neighbour and says little about ambiguity
//                (measured on cones in tests/pipeline/stereo/middlebury_test.cpp)
//   search:      every disparity of the range, or (SearchMode::kBand) coarse to fine: the pair
//                shrunk by coarse_scale and matched over the shrunk range, then kBandDisparities
//                per pixel around coarse_scale times its coarse neighbourhood's disparities, checked
//                at depth edges by the pixel's own SAD (band_placement.h; about 2.3x less CPU at
//                800x600x112; accuracy in tests/pipeline/stereo/middlebury_test.cpp)
//   validity:    +inf disparity where the pixel has no right match, fails the optional
//                left-right check, or falls below min_confidence
//
// Threads: match() uses OpenMP over a fixed number of horizontal strips; the result is
// bit-identical for any thread count. One StereoMatcher must not be used from two threads at once
// (it owns its working memory, allocated at the first frame and reused). A result's images are
// reused by a later match() only once every cv::Mat of the caller that shares them is gone.
#pragma once

#include <memory>

#include "pipeline/frame/frames.h"
#include "pipeline/stereo/stereo_config.h"

namespace cenote::pipeline {

class StereoMatcher {
 public:
  // @throws cenote::Error listing every invalid setting.
  explicit StereoMatcher(const StereoConfig& config);
  ~StereoMatcher();
  StereoMatcher(StereoMatcher&&) noexcept;
  StereoMatcher& operator=(StereoMatcher&&) noexcept;

  // @param left, right  rectified 8-bit images (grey or BGR, converted to grey), same size
  // @throws cenote::Error for empty images, different sizes or unsupported pixel types.
  DisparityMap match(const cv::Mat& left, const cv::Mat& right);

  const StereoConfig& config() const { return config_; }

 private:
  struct Impl;
  StereoConfig config_;
  std::unique_ptr<Impl> impl_;
};

// The image SAD compares under `prefilter`: for kSobelX, clamp(dI/dx, -cap, cap) + cap per pixel
// (3x3 Sobel, replicated border); for kNone the image itself. @param grey CV_8UC1.
cv::Mat prefilterForSad(const cv::Mat& grey, Prefilter prefilter, int cap);
// The same into `out`, with `derivative` (CV_16S) as scratch: both keep their memory when they
// already have the size (`out` may be a view into a larger image; it must not share grey's pixels).
void prefilterForSad(const cv::Mat& grey, Prefilter prefilter, int cap, cv::Mat& derivative, cv::Mat& out);

// The 2x2 mean of `grey` (CV_8UC1), rounded: (a + b + c + d + 2) / 4; an odd last row or column
// averages with itself. Size ((cols + 1) / 2, (rows + 1) / 2).
void halveImage(const cv::Mat& grey, cv::Mat& half);
// `grey` halved log2(scale) times (scale a power of two): the coarse level of SearchMode::kBand.
void shrinkImage(const cv::Mat& grey, int scale, cv::Mat& out);

// Z = f * b / d per pixel; +inf where the disparity is invalid or not positive.
// @param focal_px rectified focal length, @param baseline_m stereo baseline.
cv::Mat disparityToDepth(const cv::Mat& disparity, double focal_px, double baseline_m);
// The same into `depth`, which must be CV_32FC1 of the disparity's size (a recycled image).
void disparityToDepth(const cv::Mat& disparity, double focal_px, double baseline_m, cv::Mat& depth);

}  // namespace cenote::pipeline
