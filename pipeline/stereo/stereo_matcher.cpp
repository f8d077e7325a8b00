#include "pipeline/stereo/stereo_matcher.h"

#include <omp.h>

#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/error.h"
#include "pipeline/stereo/sgm_engine.h"

namespace cenote::pipeline {
namespace {

cv::Mat toGrey(const cv::Mat& image, const char* which) {
  if (image.empty()) throw Error(std::string("stereo: ") + which + " image is empty");
  if (image.depth() != CV_8U) {
    throw Error(std::string("stereo: ") + which + " image must be 8-bit, got depth " +
                std::to_string(image.depth()));
  }
  if (image.channels() == 1) return image;
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  } else {
    throw Error(std::string("stereo: ") + which + " image has " + std::to_string(image.channels()) +
                " channels; expected 1, 3 or 4");
  }
  return grey;
}

std::string sizeText(const cv::Mat& m) { return std::to_string(m.cols) + "x" + std::to_string(m.rows); }

}  // namespace

struct StereoMatcher::Impl {
  detail::SgmParams params;
  std::vector<detail::SgmWorkspace> workspaces;  // one per strip
  cv::Mat guide_bordered;                        // grey left image, for the adaptive P2
  cv::Mat left_bordered, right_bordered;         // what the cost compares
  cv::Mat census_left, census_right;
};

StereoMatcher::StereoMatcher(const StereoConfig& config) : config_(config), impl_(std::make_unique<Impl>()) {
  throwIfInvalid(config_.validate(), "stereo configuration");
  detail::SgmParams& p = impl_->params;
  p.num_disparities = config_.num_disparities;
  p.min_disparity = config_.min_disparity_px;
  p.census = config_.cost == MatchingCost::kCensus;
  p.window = config_.window_px;
  p.sad_shift = p.census ? 0 : config_.sadShift();
  p.max_cost = config_.maxCost();
  p.p1 = config_.effectiveP1();
  p.p2 = config_.effectiveP2();
  p.adaptive_p2 = config_.adaptive_p2;
  p.p2_gradient_scale = static_cast<float>(config_.p2_gradient_scale);
  p.eight_paths = config_.num_paths == 8;
  p.subpixel = config_.subpixel;
  p.pkrn_exclude_neighbours = config_.pkrn_exclude_neighbours;
  p.lr_check = config_.lr_check;
  p.invalidate_truncated = config_.invalidate_truncated;
  p.lr_max_diff = config_.lr_max_diff_px;
  p.min_confidence = static_cast<float>(config_.min_confidence);
}

StereoMatcher::~StereoMatcher() = default;
StereoMatcher::StereoMatcher(StereoMatcher&&) noexcept = default;
StereoMatcher& StereoMatcher::operator=(StereoMatcher&&) noexcept = default;

DisparityMap StereoMatcher::match(const cv::Mat& left_in, const cv::Mat& right_in) {
  const cv::Mat left = toGrey(left_in, "left");
  const cv::Mat right = toGrey(right_in, "right");
  if (left.size() != right.size()) {
    throw Error("stereo: right image is " + sizeText(right) + " but left is " + sizeText(left));
  }
  Impl& impl = *impl_;
  detail::SgmParams& p = impl.params;
  p.width = left.cols;
  p.height = left.rows;
  const int b = detail::kImageBorder;
  const bool prefiltered = !p.census && config_.prefilter != Prefilter::kNone;
  cv::copyMakeBorder(left, impl.guide_bordered, b, b, b, b, cv::BORDER_REPLICATE);
  if (prefiltered) {
    cv::copyMakeBorder(prefilterForSad(left, config_.prefilter, config_.prefilter_cap), impl.left_bordered, b, b, b,
                       b, cv::BORDER_REPLICATE);
    cv::copyMakeBorder(prefilterForSad(right, config_.prefilter, config_.prefilter_cap), impl.right_bordered, b, b,
                       b, b, cv::BORDER_REPLICATE);
  } else {
    impl.left_bordered = impl.guide_bordered;
    cv::copyMakeBorder(right, impl.right_bordered, b, b, b, b, cv::BORDER_REPLICATE);
  }
  detail::SgmImages images;
  images.guide = impl.guide_bordered.ptr<uint8_t>(b) + b;
  images.left = impl.left_bordered.ptr<uint8_t>(b) + b;
  images.right = impl.right_bordered.ptr<uint8_t>(b) + b;
  images.image_stride = static_cast<std::ptrdiff_t>(impl.left_bordered.step[0]);

  const int strips = std::min(config_.num_strips, p.height);
  if (p.census) {
    impl.census_left.create(p.height, p.width, CV_32SC1);
    impl.census_right.create(p.height, p.width, CV_32SC1);
    const std::ptrdiff_t cstride = static_cast<std::ptrdiff_t>(impl.census_left.step[0] / 4);
#pragma omp parallel for schedule(static)
    for (int s = 0; s < 2 * strips; ++s) {
      const int strip = s % strips;
      const int y0 = strip * p.height / strips, y1 = (strip + 1) * p.height / strips;
      const bool is_left = s < strips;
      detail::censusTransform(is_left ? images.left : images.right, images.image_stride, p.width, y0, y1,
                              p.window, (is_left ? impl.census_left : impl.census_right).ptr<uint32_t>(),
                              cstride);
    }
    images.census_left = impl.census_left.ptr<uint32_t>();
    images.census_right = impl.census_right.ptr<uint32_t>();
    images.census_stride = cstride;
  }

  DisparityMap result;
  result.disparity.create(p.height, p.width, CV_32FC1);
  result.confidence.create(p.height, p.width, CV_32FC1);
  detail::SgmOutput output;
  output.disparity = result.disparity.ptr<float>();
  output.confidence = result.confidence.ptr<float>();
  output.stride = static_cast<std::ptrdiff_t>(result.disparity.step[0] / sizeof(float));

  if (static_cast<int>(impl.workspaces.size()) < strips) impl.workspaces.resize(strips);
  // Dynamic schedule: strips are equal in work but threads may not be equally free.
#pragma omp parallel for schedule(dynamic, 1)
  for (int s = 0; s < strips; ++s) {
    const int y0 = s * p.height / strips, y1 = (s + 1) * p.height / strips;
    detail::matchStrip(p, images, y0, y1, config_.strip_overlap_px, impl.workspaces[s], output);
  }
  return result;
}

cv::Mat prefilterForSad(const cv::Mat& grey, Prefilter prefilter, int cap) {
  if (prefilter == Prefilter::kNone) return grey;
  cv::Mat derivative;
  cv::Sobel(grey, derivative, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  cv::Mat out(grey.size(), CV_8UC1);
  for (int y = 0; y < grey.rows; ++y) {
    const int16_t* in = derivative.ptr<int16_t>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < grey.cols; ++x) o[x] = static_cast<uint8_t>(std::clamp<int>(in[x], -cap, cap) + cap);
  }
  return out;
}

cv::Mat disparityToDepth(const cv::Mat& disparity, double focal_px, double baseline_m) {
  if (disparity.type() != CV_32FC1) throw Error("disparityToDepth: disparity must be CV_32FC1");
  cv::Mat depth(disparity.size(), CV_32FC1);
  const float fb = static_cast<float>(focal_px * baseline_m);
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    float* z = depth.ptr<float>(y);
    for (int x = 0; x < disparity.cols; ++x) {
      z[x] = (std::isfinite(d[x]) && d[x] > 0.0f) ? fb / d[x] : std::numeric_limits<float>::infinity();
    }
  }
  return depth;
}

}  // namespace cenote::pipeline
