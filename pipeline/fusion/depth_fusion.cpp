#include "pipeline/fusion/depth_fusion.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/error.h"
#include "pipeline/frame/pose_check.h"

namespace cenote::pipeline {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kMaxViews = FusionConfig::kMaxViews;

// One cell of a rendered map.
struct Cell {
  float depth_m;
  float confidence;
};
static_assert(sizeof(Cell) == 2 * sizeof(float));

// Maps pixel (x, y) of view `from` with depth Z to view `to`: h = Z * (A [x y 1]^T) + k, pixel
// (h0 / h2, h1 / h2), depth h2 (K's last row is 0 0 1). A = K_to R_to_from K_from^-1, k = K_to t_to_from.
struct Projector {
  float a[9];
  float k[3];
};

Projector makeProjector(const DepthFrame& to, const DepthFrame& from) {
  const Eigen::Isometry3d T_to_from = to.T_world_cam.inverse() * from.T_world_cam;
  const Eigen::Matrix3d A = to.K * T_to_from.linear() * from.K.inverse();
  const Eigen::Vector3d k = to.K * T_to_from.translation();
  Projector p;
  for (int i = 0; i < 9; ++i) p.a[i] = static_cast<float>(A(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) p.k[i] = static_cast<float>(k(i));
  return p;
}

// Rule 0 of the header, in float.
struct Validity {
  float max_depth_m;     // finite
  float min_confidence;  // > 0
  bool operator()(float depth_m, float confidence) const {
    return depth_m > 0.0f && depth_m <= max_depth_m && confidence >= min_confidence;  // NaN fails
  }
};

// eps(Z) of the header.
struct SupportRadiusFn {
  bool relative;
  float eps;
  float operator()(float depth_m) const { return relative ? eps * depth_m : eps; }
};

std::string describe(const DepthFrame& frame) {
  std::ostringstream text;
  text << "fusion: frame t = " << std::fixed;
  text.precision(3);
  text << frame.t_s << " s";
  return text.str();
}

// Step 1: z-buffer of view `source` in the reference view. One thread writes `out`.
void renderView(const DepthFrame& source, const Projector& P, const Validity& valid, cv::Mat& out) {
  out.setTo(cv::Scalar(kInf, 0.0f));
  const int width = out.cols, height = out.rows;
  const float width_f = static_cast<float>(width), height_f = static_cast<float>(height);
  Cell* cells = out.ptr<Cell>(0);
  for (int y = 0; y < source.depth.rows; ++y) {
    const float* depth = source.depth.ptr<float>(y);
    const float* conf = source.confidence.ptr<float>(y);
    const float yf = static_cast<float>(y);
    const float b0 = P.a[1] * yf + P.a[2], b1 = P.a[4] * yf + P.a[5], b2 = P.a[7] * yf + P.a[8];
    for (int x = 0; x < source.depth.cols; ++x) {
      const float z = depth[x], c = conf[x];
      if (!valid(z, c)) continue;
      const float xf = static_cast<float>(x);
      const float hz = z * (b2 + P.a[6] * xf) + P.k[2];
      if (!(hz > 0.0f)) continue;
      const float inv = 1.0f / hz;
      const float u = (z * (b0 + P.a[0] * xf) + P.k[0]) * inv;
      const float v = (z * (b1 + P.a[3] * xf) + P.k[1]) * inv;
      if (!(u >= -0.5f && u < width_f && v >= -0.5f && v < height_f)) continue;
      const int iu = static_cast<int>(u + 0.5f), iv = static_cast<int>(v + 0.5f);
      if (iu >= width || iv >= height) continue;
      Cell& cell = cells[static_cast<size_t>(iv) * width + iu];
      if (hz < cell.depth_m) cell = {hz, c};
    }
  }
}

// Everything the per-pixel fusion needs, resolved once per call.
struct FusionSetup {
  int num_views = 0, ref = 0, width = 0, height = 0;
  std::array<const float*, kMaxViews> depth{}, conf{};  // original maps (row 0; continuous rows of `step` floats)
  std::array<size_t, kMaxViews> step{};                  // in floats
  std::array<const Cell*, kMaxViews> rendered{};         // rendered maps (ref: unused)
  std::array<Projector, kMaxViews> to_view{};            // reference pixel -> view l (ref: unused)
  Validity valid{};
  SupportRadiusFn eps{};
  float min_fused_confidence = 0.0f;
};

// Steps 2-4 for one row of the reference view.
void fuseRow(const FusionSetup& s, int y, float* out_depth, float* out_conf) {
  const int n_views = s.num_views, r = s.ref;
  const float yf = static_cast<float>(y);
  std::array<std::array<float, 3>, kMaxViews> base{};
  for (int l = 0; l < n_views; ++l) {
    if (l == r) continue;
    const float* a = s.to_view[l].a;
    base[l] = {a[1] * yf + a[2], a[4] * yf + a[5], a[7] * yf + a[8]};
  }
  const float* ref_depth = s.depth[r] + y * s.step[r];
  const float* ref_conf = s.conf[r] + y * s.step[r];
  const size_t row_offset = static_cast<size_t>(y) * s.width;
  const float width_f = static_cast<float>(s.width), height_f = static_cast<float>(s.height);

  for (int x = 0; x < s.width; ++x) {
    // Step 2: candidates.
    std::array<float, kMaxViews> z, c;
    std::array<int, kMaxViews> view;
    int n = 0;
    for (int v = 0; v < n_views; ++v) {
      float zv, cv;
      if (v == r) {
        zv = ref_depth[x];
        cv = ref_conf[x];
        if (!s.valid(zv, cv)) continue;
      } else {
        const Cell cell = s.rendered[v][row_offset + x];
        if (!(cell.depth_m < kInf)) continue;
        zv = cell.depth_m;
        cv = cell.confidence;
      }
      z[n] = zv;
      c[n] = cv;
      view[n] = v;
      ++n;
    }
    const float ref_z = ref_depth[x], ref_c = ref_conf[x];
    const bool ref_valid = s.valid(ref_z, ref_c);
    const float xf = static_cast<float>(x);

    // Step 3 and 4: a candidate can win only when its support minus occlusion (an upper bound of
    // its fused confidence, since free-space terms only subtract) beats the best so far, so the
    // free-space projections are skipped otherwise; the result is the same as evaluating all.
    bool have_best = false;
    float best_conf = s.min_fused_confidence, best_depth = kInf;
    for (int j = 0; j < n; ++j) {
      const float zj = z[j], e = s.eps(zj);
      float support = 0.0f, weighted = 0.0f, occlusion = 0.0f;
      for (int i = 0; i < n; ++i) {
        const float diff = z[i] - zj;
        if (std::abs(diff) < e) {
          support += c[i];
          weighted += c[i] * z[i];
        } else if (diff < -e) {
          occlusion += c[i];
        }
      }
      const float upper = support - occlusion;
      if (have_best ? !(upper > best_conf) : !(upper >= best_conf)) continue;
      float free_space = 0.0f;
      for (int l = 0; l < n_views; ++l) {
        if (l == view[j]) continue;
        if (l == r) {
          if (ref_valid && zj < ref_z - e) free_space += ref_c;
          continue;
        }
        const Projector& P = s.to_view[l];
        const float hz = zj * (base[l][2] + P.a[6] * xf) + P.k[2];
        if (!(hz > 0.0f)) continue;
        const float inv = 1.0f / hz;
        const float u = (zj * (base[l][0] + P.a[0] * xf) + P.k[0]) * inv;
        const float v = (zj * (base[l][1] + P.a[3] * xf) + P.k[1]) * inv;
        if (!(u >= -0.5f && u < width_f && v >= -0.5f && v < height_f)) continue;
        const int iu = static_cast<int>(u + 0.5f), iv = static_cast<int>(v + 0.5f);
        if (iu >= s.width || iv >= s.height) continue;
        const size_t q = static_cast<size_t>(iv) * s.step[l] + iu;
        const float zl = s.depth[l][q], cl = s.conf[l][q];
        if (s.valid(zl, cl) && hz < zl - s.eps(hz)) free_space += cl;
      }
      const float fused = upper - free_space;
      if (have_best ? fused > best_conf : fused >= best_conf) {
        have_best = true;
        best_conf = fused;
        best_depth = weighted / support;
      }
    }
    out_depth[x] = have_best ? best_depth : kInf;
    out_conf[x] = have_best ? best_conf : 0.0f;
  }
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void checkFusionInput(const DepthFrame& frame, cv::Size expected_size) {
  const std::string what = describe(frame);
  if (frame.depth.empty()) throw Error(what + ": depth map is empty");
  if (frame.depth.type() != CV_32FC1) throw Error(what + ": depth map must be CV_32FC1 (float metres)");
  if (frame.confidence.type() != CV_32FC1 || frame.confidence.size() != frame.depth.size()) {
    throw Error(what + ": confidence map must be CV_32FC1 of the depth map's size " +
                std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows));
  }
  if (!frame.color.empty() && (frame.color.type() != CV_8UC3 || frame.color.size() != frame.depth.size())) {
    throw Error(what + ": colour image must be CV_8UC3 of the depth map's size " + std::to_string(frame.depth.cols) +
                "x" + std::to_string(frame.depth.rows));
  }
  if (!expected_size.empty() && frame.depth.size() != expected_size) {
    throw Error(what + ": depth map is " + std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows) +
                " but the other views are " + std::to_string(expected_size.width) + "x" +
                std::to_string(expected_size.height));
  }
  checkIntrinsics(frame.K, what);
  checkPose(frame.T_world_cam, what);
}

void fuseViews(std::span<const DepthFrame* const> views, const FusionConfig& config, FusionScratch& scratch,
               DepthFrame& fused, FusionTimings* timings) {
  throwIfInvalid(config.validate(), "fusion");
  const int n_views = config.num_views;
  if (static_cast<int>(views.size()) != n_views) {
    throw Error("fusion: got " + std::to_string(views.size()) + " views, fusion.num_views is " +
                std::to_string(n_views));
  }
  const int r = (n_views - 1) / 2;
  const DepthFrame& ref = *views[r];
  checkFusionInput(ref, {});
  const cv::Size size = ref.depth.size();
  for (const DepthFrame* view : views) checkFusionInput(*view, size);

  FusionSetup s;
  s.num_views = n_views;
  s.ref = r;
  s.width = size.width;
  s.height = size.height;
  s.valid.max_depth_m = static_cast<float>(std::min<double>(config.max_depth_m, std::numeric_limits<float>::max()));
  s.valid.min_confidence =
      std::max(static_cast<float>(config.min_input_confidence), std::numeric_limits<float>::denorm_min());
  s.eps = {config.support_radius == SupportRadius::kRelative, static_cast<float>(config.eps)};
  s.min_fused_confidence = static_cast<float>(config.min_fused_confidence);

  scratch.rendered.resize(n_views);
  for (int v = 0; v < n_views; ++v) {
    const DepthFrame& view = *views[v];
    if (!view.depth.isContinuous() || !view.confidence.isContinuous() || view.depth.step != view.confidence.step) {
      throw Error(describe(view) + ": depth and confidence maps must be continuous (clone() a region of interest)");
    }
    s.depth[v] = view.depth.ptr<float>(0);
    s.conf[v] = view.confidence.ptr<float>(0);
    s.step[v] = view.depth.step1();
    if (v == r) continue;
    scratch.rendered[v].create(size, CV_32FC2);
    s.rendered[v] = scratch.rendered[v].ptr<Cell>(0);
    s.to_view[v] = makeProjector(view, ref);
  }

  // Step 1: one task per view, each writing only its own z-buffer.
  auto start = std::chrono::steady_clock::now();
  std::array<Projector, kMaxViews> to_ref{};
  for (int v = 0; v < n_views; ++v) {
    if (v != r) to_ref[v] = makeProjector(ref, *views[v]);
  }
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < n_views - 1; ++t) {
    const int v = t < r ? t : t + 1;
    renderView(*views[v], to_ref[v], s.valid, scratch.rendered[v]);
  }
  if (timings) timings->render_ms = msSince(start);

  // Steps 2-4: rows are independent; each output pixel is written by one thread.
  start = std::chrono::steady_clock::now();
  fused.depth.create(size, CV_32FC1);
  fused.confidence.create(size, CV_32FC1);
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < size.height; ++y) {
    fuseRow(s, y, fused.depth.ptr<float>(y), fused.confidence.ptr<float>(y));
  }
  if (timings) timings->fuse_ms = msSince(start);

  fused.t_s = ref.t_s;
  fused.color = ref.color;
  fused.K = ref.K;
  fused.T_world_cam = ref.T_world_cam;
}

DepthFrame fuseViews(const std::vector<DepthFrame>& views, const FusionConfig& config) {
  std::vector<const DepthFrame*> pointers;
  for (const DepthFrame& view : views) pointers.push_back(&view);
  FusionScratch scratch;
  DepthFrame fused;
  fuseViews(pointers, config, scratch, fused);
  return fused;
}

}  // namespace cenote::pipeline
