#include "pipeline/stereo/stereo_matcher.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "common/error.h"
#include "io/image/mat_recycler.h"
#include "pipeline/stereo/band_placement.h"
#include "pipeline/stereo/matcher_kernels.h"
#include "pipeline/stereo/sgm_engine.h"

namespace cenote::pipeline {
namespace {

// Result images kept for reuse: the disparities and confidences of the frames a pipeline holds
// at once (its queues, the fusion window), and a few more.
constexpr std::size_t kRecycledResults = 16;

// `image` as grey: itself, or converted into `grey` (kept by the matcher, so its memory is reused).
cv::Mat toGrey(const cv::Mat& image, const char* which, cv::Mat& grey) {
  if (image.empty()) throw Error(std::string("stereo: ") + which + " image is empty");
  if (image.depth() != CV_8U) {
    throw Error(std::string("stereo: ") + which + " image must be 8-bit, got depth " + std::to_string(image.depth()));
  }
  if (image.channels() == 1) return image;
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

static_assert(detail::kImageBorder >= detail::kEdgeCheckBorder, "the edge check reads the matcher's bordered images");

// One resolution of the match: its parameters, bordered images and per-strip memory.
struct MatchLevel {
  detail::SgmParams params;
  std::vector<detail::SgmWorkspace> workspaces;  // one per strip
  cv::Mat guide_bordered;                        // grey left image, for the adaptive P2
  cv::Mat left_bordered, right_bordered;         // what the cost compares
  cv::Mat census_left, census_right;
  cv::Mat derivative[2];     // per side (left, right): prefilterForSad()'s scratch
  detail::SgmImages images;  // views of the above
};

// Coarse to fine, per strip: the strip's own coarse match (so that a strip never waits for
// another) and the bands placed from it; full image size, only the strip's rows written.
struct StripBands {
  cv::Mat coarse_disparity, coarse_confidence;  // CV_32F, the coarse size
  cv::Mat band_start;                           // CV_16S: first disparity index searched per pixel
  detail::BandScratch scratch;                  // placeBands()' memory
};

struct StereoMatcher::Impl {
  MatchLevel full;
  MatchLevel coarse;  // coarse to fine only: the pair shrunk by coarse_scale
  cv::Mat coarse_left, coarse_right;
  std::vector<StripBands> bands;  // one per strip
  cv::Mat grey_left, grey_right;  // colour inputs converted
  // The results' images, reused once the caller has dropped them (a frame's confidence lives on
  // in the fusion window): a fresh 4 MB per frame at 800x600 would be page-faulted in each time.
  io::MatRecycler results{kRecycledResults};
};

detail::SgmParams detail::paramsOf(const StereoConfig& config) {
  detail::SgmParams p;
  p.num_disparities = config.num_disparities;
  p.min_disparity = config.min_disparity_px;
  p.census = config.cost == MatchingCost::kCensus;
  p.window = config.window_px;
  p.sad_shift = p.census ? 0 : config.sadShift();
  p.max_cost = config.maxCost();
  p.p1 = config.effectiveP1();
  p.p2 = config.effectiveP2();
  p.adaptive_p2 = config.adaptive_p2;
  p.p2_gradient_scale = static_cast<float>(config.p2_gradient_scale);
  p.eight_paths = config.num_paths == 8;
  p.subpixel = config.subpixel;
  p.pkrn_exclude_neighbours = config.pkrn_exclude_neighbours;
  p.lr_check = config.lr_check;
  p.invalidate_truncated = config.invalidate_truncated;
  p.lr_max_diff = config.lr_max_diff_px;
  p.min_confidence = static_cast<float>(config.min_confidence);
  return p;
}

namespace {

// Replicates the outermost pixels of `bordered`'s interior (all but `b` pixels on each side) into
// its border, as cv::copyMakeBorder(BORDER_REPLICATE) would: rows first, then the top and bottom.
void replicateBorder(cv::Mat& bordered, int b) {
  const int width = bordered.cols - 2 * b, height = bordered.rows - 2 * b;
  for (int y = b; y < b + height; ++y) {
    uint8_t* row = bordered.ptr<uint8_t>(y);
    std::memset(row, row[b], b);
    std::memset(row + b + width, row[b + width - 1], b);
  }
  for (int y = 0; y < b; ++y) {
    std::memcpy(bordered.ptr<uint8_t>(y), bordered.ptr<uint8_t>(b), bordered.cols);
    std::memcpy(bordered.ptr<uint8_t>(b + height + y), bordered.ptr<uint8_t>(b + height - 1), bordered.cols);
  }
}

// Borders and prefilters one image of a pair for matching at its size (the left one also as
// the guide of the adaptive P2). The two sides touch different members: they may run at once.
void prepareSide(MatchLevel& level, const StereoConfig& config, const cv::Mat& image, bool is_left) {
  const int b = detail::kImageBorder;
  const bool prefiltered = !level.params.census && config.prefilter != Prefilter::kNone;
  cv::Mat& bordered = is_left ? level.left_bordered : level.right_bordered;
  if (is_left) cv::copyMakeBorder(image, level.guide_bordered, b, b, b, b, cv::BORDER_REPLICATE);
  if (prefiltered) {
    // Prefiltered straight into the bordered image's interior (no copy of it), then bordered.
    bordered.create(image.rows + 2 * b, image.cols + 2 * b, CV_8UC1);
    cv::Mat interior = bordered(cv::Rect(b, b, image.cols, image.rows));
    prefilterForSad(image, config.prefilter, config.prefilter_cap, level.derivative[is_left ? 0 : 1], interior);
    replicateBorder(bordered, b);
  } else if (is_left) {
    bordered = level.guide_bordered;
  } else {
    cv::copyMakeBorder(image, bordered, b, b, b, b, cv::BORDER_REPLICATE);
  }
}

// The engine's views of a prepared level (and room for its census descriptors).
void finishLevel(MatchLevel& level, cv::Size size) {
  detail::SgmParams& p = level.params;
  p.width = size.width;
  p.height = size.height;
  const int b = detail::kImageBorder;
  detail::SgmImages& images = level.images;
  images = detail::SgmImages{};
  images.guide = level.guide_bordered.ptr<uint8_t>(b) + b;
  images.left = level.left_bordered.ptr<uint8_t>(b) + b;
  images.right = level.right_bordered.ptr<uint8_t>(b) + b;
  images.image_stride = static_cast<std::ptrdiff_t>(level.left_bordered.step[0]);
  if (p.census) {
    level.census_left.create(p.height, p.width, CV_32SC1);
    level.census_right.create(p.height, p.width, CV_32SC1);
    images.census_left = level.census_left.ptr<uint32_t>();
    images.census_right = level.census_right.ptr<uint32_t>();
    images.census_stride = static_cast<std::ptrdiff_t>(level.census_left.step[0] / 4);
  }
}

// Census descriptors of both images of the levels, in row blocks shared by the threads of the
// enclosing parallel region (an orphaned omp for: every thread of the region must call it).
void censusTransforms(const std::vector<MatchLevel*>& levels) {
  constexpr int kParts = 4;  // row blocks per image
  const int jobs = static_cast<int>(levels.size()) * 2 * kParts;
#pragma omp for schedule(dynamic, 1)
  for (int i = 0; i < jobs; ++i) {
    MatchLevel& level = *levels[i / (2 * kParts)];
    const int j = i % (2 * kParts);  // left parts, then right
    const detail::SgmParams& p = level.params;
    const detail::SgmImages& images = level.images;
    const int part = j % kParts;
    const bool is_left = j < kParts;
    const int y0 = part * p.height / kParts, y1 = (part + 1) * p.height / kParts;
    detail::censusTransform(is_left ? images.left : images.right, images.image_stride, p.width, y0, y1, p.window,
                            (is_left ? level.census_left : level.census_right).ptr<uint32_t>(), images.census_stride);
  }
}

detail::SgmOutput outputOf(DisparityMap& map, const detail::SgmParams& p) {
  map.disparity.create(p.height, p.width, CV_32FC1);
  map.confidence.create(p.height, p.width, CV_32FC1);
  detail::SgmOutput output;
  output.disparity = map.disparity.ptr<float>();
  output.confidence = map.confidence.ptr<float>();
  output.stride = static_cast<std::ptrdiff_t>(map.disparity.step[0] / sizeof(float));
  return output;
}

// First rows of `strips` strips of an image `height` rows high, and `height` at the end. Every
// strip gets the same number of rows to match, its warm-up rows included (`overlap` above every
// strip but the first, and with 8 paths below every strip but the last), so that a thread with the
// first strip does not wait for one with a warm-up. Depends on the image and the settings only,
// never on the thread count. At least one row per strip (strips <= height).
std::vector<int> stripBoundaries(int strips, int height, int overlap, bool eight_paths) {
  std::vector<int> begin(strips + 1, 0);
  begin[strips] = height;
  const int sides = eight_paths ? 2 : 1;  // warm-ups per boundary between strips
  const double rows_per_strip = (height + static_cast<double>(sides) * (strips - 1) * overlap) / strips;
  for (int s = 1; s < strips; ++s) {
    // Warm-ups of strips 0 .. s - 1: a top one for each but the first, and with 8 paths a bottom one
    // for each.
    const int warmups_before = sides * s - 1;
    const int y = static_cast<int>(std::lround(s * rows_per_strip - warmups_before * overlap));
    begin[s] = std::clamp(y, begin[s - 1] + 1, height - (strips - s));
  }
  return begin;
}

}  // namespace

StereoMatcher::StereoMatcher(const StereoConfig& config) : config_(config), impl_(std::make_unique<Impl>()) {
  throwIfInvalid(config_.validate(), "stereo configuration");
  impl_->full.params = detail::paramsOf(config_);
  impl_->coarse.params = detail::paramsOf(config_.coarseConfig());
}

StereoMatcher::~StereoMatcher() = default;
StereoMatcher::StereoMatcher(StereoMatcher&&) noexcept = default;
StereoMatcher& StereoMatcher::operator=(StereoMatcher&&) noexcept = default;

DisparityMap StereoMatcher::match(const cv::Mat& left_in, const cv::Mat& right_in) {
  Impl& impl = *impl_;
  const cv::Mat left = toGrey(left_in, "left", impl.grey_left);
  const cv::Mat right = toGrey(right_in, "right", impl.grey_right);
  if (left.size() != right.size()) {
    throw Error("stereo: right image is " + sizeText(right) + " but left is " + sizeText(left));
  }
  const bool band = config_.usesBand();
  detail::SgmParams& p = impl.full.params;
  const detail::SgmParams& pc = impl.coarse.params;
  p.width = left.cols;
  p.height = left.rows;
  DisparityMap result{impl.results.take(p.height, p.width, CV_32FC1), impl.results.take(p.height, p.width, CV_32FC1)};
  const detail::SgmOutput output = outputOf(result, p);
  const int strips = std::min(config_.num_strips, p.height);
  const std::vector<int> strip_begin = stripBoundaries(strips, p.height, config_.strip_overlap_px, p.eight_paths);
  const int overlap = config_.strip_overlap_px;
  if (static_cast<int>(impl.full.workspaces.size()) < strips) impl.full.workspaces.resize(strips);
  if (band) {
    if (static_cast<int>(impl.coarse.workspaces.size()) < strips) impl.coarse.workspaces.resize(strips);
    if (static_cast<int>(impl.bands.size()) < strips) impl.bands.resize(strips);
  }
  std::vector<MatchLevel*> census_levels;
  if (p.census) census_levels.push_back(&impl.full);
  if (p.census && band) census_levels.push_back(&impl.coarse);

    // One parallel region per frame (each region hands work to the other thread, which spins
    // between regions): the two images prepared side by side, the census descriptors, then the
    // strips. Strips are equal in work (stripBoundaries) but threads may not be equally free
    // (dynamic schedule), and a strip never waits for another.
#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (int side = 0; side < 2; ++side) {
      const cv::Mat& image = side == 0 ? left : right;
      prepareSide(impl.full, config_, image, side == 0);
      if (band) {
        cv::Mat& coarse = side == 0 ? impl.coarse_left : impl.coarse_right;
        shrinkImage(image, config_.coarse_scale, coarse);
        prepareSide(impl.coarse, config_, coarse, side == 0);
      }
    }
#pragma omp single
    {
      finishLevel(impl.full, left.size());
      if (band) finishLevel(impl.coarse, impl.coarse_left.size());
    }
    if (!census_levels.empty()) censusTransforms(census_levels);
#pragma omp for schedule(dynamic, 1)
    for (int s = 0; s < strips; ++s) {
      const int y0 = strip_begin[s], y1 = strip_begin[s + 1];
      detail::SgmImages images = impl.full.images;
      if (band) {
        // Rows this strip reads (warm-up included), their coarse rows, and the coarse match of
        // those with its own warm-up.
        StripBands& sb = impl.bands[s];
        const int scale = config_.coarse_scale;
        const int fine_begin = std::max(0, y0 - overlap);
        const int fine_end = p.eight_paths ? std::min(p.height, y1 + overlap) : y1;
        const int coarse_begin = fine_begin / scale, coarse_end = (fine_end - 1) / scale + 1;
        DisparityMap coarse{sb.coarse_disparity, sb.coarse_confidence};
        const detail::SgmOutput coarse_output = outputOf(coarse, pc);
        sb.coarse_disparity = coarse.disparity;
        sb.coarse_confidence = coarse.confidence;
        detail::matchStrip(pc, impl.coarse.images, coarse_begin, coarse_end, (overlap + scale - 1) / scale,
                           impl.coarse.workspaces[s], coarse_output);
        sb.band_start.create(p.height, p.width, CV_16SC1);
        const detail::EdgeCheckImages edge_images{images.left, images.right, images.image_stride, p.width, p.height};
        detail::placeBands(sb.coarse_disparity, config_, edge_images, coarse_begin, coarse_end, fine_begin, fine_end,
                           sb.scratch, sb.band_start);
        images.band_start = sb.band_start.ptr<int16_t>();
        images.band_stride = static_cast<std::ptrdiff_t>(sb.band_start.step[0] / sizeof(int16_t));
      }
      detail::matchStrip(p, images, y0, y1, overlap, impl.full.workspaces[s], output);
    }
  }
  return result;
}

void shrinkImage(const cv::Mat& grey, int scale, cv::Mat& out) {
  if (scale <= 1) {
    grey.copyTo(out);
    return;
  }
  // The halvings before the last go through scratch images kept per thread, and the last writes
  // `out` in place: a frame allocates nothing once the sizes are known (the matcher keeps `out`).
  thread_local cv::Mat scratch[2];
  const cv::Mat* in = &grey;
  for (int s = scale, k = 0; s > 2; s /= 2, k ^= 1) {
    halveImage(*in, scratch[k]);
    in = &scratch[k];
  }
  halveImage(*in, out);
}

void halveImage(const cv::Mat& grey, cv::Mat& half) {
  half.create((grey.rows + 1) / 2, (grey.cols + 1) / 2, CV_8UC1);
  const int last_row = grey.rows - 1;
  for (int y = 0; y < half.rows; ++y) {
    detail::halveRow(grey.ptr<uint8_t>(2 * y), grey.ptr<uint8_t>(std::min(2 * y + 1, last_row)), grey.cols, half.cols,
                     half.ptr<uint8_t>(y));
  }
}

cv::Mat prefilterForSad(const cv::Mat& grey, Prefilter prefilter, int cap) {
  if (prefilter == Prefilter::kNone) return grey;
  cv::Mat derivative, out;
  prefilterForSad(grey, prefilter, cap, derivative, out);
  return out;
}

void prefilterForSad(const cv::Mat& grey, Prefilter prefilter, int cap, cv::Mat& derivative, cv::Mat& out) {
  if (prefilter == Prefilter::kNone) {
    grey.copyTo(out);
    return;
  }
  cv::Sobel(grey, derivative, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  out.create(grey.size(), CV_8UC1);
  for (int y = 0; y < grey.rows; ++y)
    detail::clampDerivativeRow(derivative.ptr<int16_t>(y), grey.cols, cap, out.ptr<uint8_t>(y));
}

cv::Mat disparityToDepth(const cv::Mat& disparity, double focal_px, double baseline_m) {
  cv::Mat depth(disparity.size(), CV_32FC1);
  disparityToDepth(disparity, focal_px, baseline_m, depth);
  return depth;
}

void disparityToDepth(const cv::Mat& disparity, double focal_px, double baseline_m, cv::Mat& depth) {
  if (disparity.type() != CV_32FC1) throw Error("disparityToDepth: disparity must be CV_32FC1");
  if (depth.type() != CV_32FC1 || depth.size() != disparity.size()) {
    throw Error("disparityToDepth: depth must be CV_32FC1 of the disparity's size");
  }
  const float fb = static_cast<float>(focal_px * baseline_m);
  for (int y = 0; y < disparity.rows; ++y) {
    detail::depthFromDisparityRow(disparity.ptr<float>(y), disparity.cols, fb, depth.ptr<float>(y));
  }
}

}  // namespace cenote::pipeline
