#include "pipeline/fusion/depth_fusion.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/error.h"
#include "common/pose_check.h"
#include "pipeline/fusion/fusion_kernels.h"

namespace cenote::pipeline {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kMaxViews = FusionConfig::kMaxViews;

using detail::FusionLimits;
using detail::FusionRowInput;
using detail::Projector;

Projector makeProjector(const DepthFrame& to, const DepthFrame& from) {
  const Eigen::Isometry3d T_to_from = to.T_world_cam.inverse() * from.T_world_cam;
  const Eigen::Matrix3d A = to.K * T_to_from.linear() * from.K.inverse();
  const Eigen::Vector3d k = to.K * T_to_from.translation();
  Projector p;
  for (int i = 0; i < 9; ++i) p.a[i] = static_cast<float>(A(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) p.k[i] = static_cast<float>(k(i));
  return p;
}

bool isValid(const FusionLimits& l, float depth_m, float confidence) {
  return depth_m > 0.0f && depth_m <= l.max_depth_m && confidence >= l.min_confidence;  // NaN fails
}

float epsAt(const FusionLimits& l, float depth_m) { return l.relative_eps ? l.eps * depth_m : l.eps; }

std::string describe(const DepthFrame& frame) {
  std::ostringstream text;
  text << "fusion: frame t = " << std::fixed;
  text.precision(3);
  text << frame.t_s << " s";
  return text.str();
}

// Scalar form of detail::projectRow(), for rows narrower than one vector.
int32_t projectRowScalar(const Projector& P, const FusionLimits& limits, const float* depth, const float* conf, int y,
                         int width, int target_width, int target_height, int32_t* out_index, float* out_depth) {
  int32_t max_index = -1;
  const float yf = static_cast<float>(y);
  const float b0 = P.a[1] * yf + P.a[2], b1 = P.a[4] * yf + P.a[5], b2 = P.a[7] * yf + P.a[8];
  for (int x = 0; x < width; ++x) {
    out_index[x] = -1;
    const float z = depth[x], xf = static_cast<float>(x);
    if (!isValid(limits, z, conf[x])) continue;
    const float hz = z * (b2 + P.a[6] * xf) + P.k[2];
    if (!(hz > 0.0f)) continue;
    const float inv = 1.0f / hz;
    const float u = (z * (b0 + P.a[0] * xf) + P.k[0]) * inv, v = (z * (b1 + P.a[3] * xf) + P.k[1]) * inv;
    if (!(u >= -0.5f && u < target_width && v >= -0.5f && v < target_height)) continue;
    const int iu = static_cast<int>(u + 0.5f), iv = static_cast<int>(v + 0.5f);
    if (iu >= target_width || iv >= target_height) continue;
    out_index[x] = iv * target_width + iu;
    out_depth[x] = hz;
    max_index = std::max(max_index, out_index[x]);
  }
  return max_index;
}

// Step 1 for one view: z-buffer in the reference view. Rows are projected with SIMD into a row
// buffer, then written in row-major order (nearest wins, first wins a tie). One thread per call.
void renderView(const DepthFrame& source, const Projector& P, const FusionLimits& limits, bool simd,
                FusionScratch::View& out) {
  const int width = out.depth.cols, height = out.depth.rows;
  float* z_buffer = out.depth.ptr<float>(0);
  float* c_buffer = out.confidence.ptr<float>(0);
  // Only depths are cleared (a confidence is read only where a depth was written), whole rows at
  // a time just before the first point lands in them: a source row lands near its own row, so
  // the cleared rows are still in cache when its points are written (a clear of the whole buffer
  // first had left the cache by then).
  const size_t pixels = static_cast<size_t>(width) * height;
  size_t cleared = 0;
  int32_t* index = out.row_index.data();
  float* depth = out.row_depth.data();
  for (int y = 0; y < source.depth.rows; ++y) {
    const float* conf = source.confidence.ptr<float>(y);
    const int32_t max_index = simd ? detail::projectRow(P, limits, source.depth.ptr<float>(y), conf, y, source.depth.cols,
                                                        width, height, index, depth)
                                   : projectRowScalar(P, limits, source.depth.ptr<float>(y), conf, y, source.depth.cols,
                                                      width, height, index, depth);
    if (max_index >= 0 && static_cast<size_t>(max_index) >= cleared) {
      const size_t end = (static_cast<size_t>(max_index) / width + 1) * width;
      std::fill(z_buffer + cleared, z_buffer + end, kInf);
      cleared = end;
    }
    // Dropped points (index -1) come in runs (holes, the far side of the image), so the branch
    // is mostly predicted; a point is written only when it is nearer (an equal depth keeps the first).
    for (int x = 0; x < source.depth.cols; ++x) {
      const int32_t i = index[x];
      if (i >= 0 && depth[x] < z_buffer[i]) {
        z_buffer[i] = depth[x];
        c_buffer[i] = conf[x];
      }
    }
  }
  std::fill(z_buffer + cleared, z_buffer + pixels, kInf);
}

// Scalar form of detail::fuseRow() (steps 2-4), for rows narrower than one vector.
void fuseRowScalar(const FusionRowInput& s, int y, float* out_depth, float* out_conf) {
  const int n_views = s.num_views, r = s.ref;
  const FusionLimits& lim = s.limits;
  const float yf = static_cast<float>(y);
  const float* ref_depth = s.depth[r] + y * s.step[r];
  const float* ref_conf = s.conf[r] + y * s.step[r];
  const size_t row = static_cast<size_t>(y) * s.width;
  for (int x = 0; x < s.width; ++x) {
    const float xf = static_cast<float>(x);
    std::array<float, kMaxViews> z, c;
    std::array<bool, kMaxViews> has;
    for (int v = 0; v < n_views; ++v) {
      z[v] = v == r ? ref_depth[x] : s.rendered_depth[v][row + x];
      c[v] = v == r ? ref_conf[x] : s.rendered_conf[v][row + x];
      has[v] = v == r ? isValid(lim, z[v], c[v]) : z[v] < kInf;
    }
    float best_conf = -kInf, best_depth = kInf;
    for (int j = 0; j < n_views; ++j) {
      if (!has[j]) continue;
      const float zj = z[j], e = epsAt(lim, zj);
      float support = 0.0f, weighted = 0.0f, conflict = 0.0f;
      for (int i = 0; i < n_views; ++i) {
        if (!has[i]) continue;
        const float diff = z[i] - zj;
        if (std::abs(diff) < e) {
          support += c[i];
          weighted += c[i] * z[i];
        } else if (diff < -e) {
          conflict += c[i];  // occlusion
        }
      }
      for (int l = 0; l < n_views; ++l) {
        if (l == j) continue;
        if (l == r) {
          if (has[r] && zj < z[r] - e) conflict += c[r];
          continue;
        }
        const Projector& P = s.to_view[l];
        const float hz = zj * (P.a[6] * xf + (P.a[7] * yf + P.a[8])) + P.k[2];
        if (!(hz > 0.0f)) continue;
        const float inv = 1.0f / hz;
        const float u = (zj * (P.a[0] * xf + (P.a[1] * yf + P.a[2])) + P.k[0]) * inv;
        const float v = (zj * (P.a[3] * xf + (P.a[4] * yf + P.a[5])) + P.k[1]) * inv;
        if (!(u >= -0.5f && u < s.width && v >= -0.5f && v < s.height)) continue;
        const int iu = static_cast<int>(u + 0.5f), iv = static_cast<int>(v + 0.5f);
        if (iu >= s.width || iv >= s.height) continue;
        const size_t q = static_cast<size_t>(iv) * s.step[l] + iu;
        const float zl = s.depth[l][q], cl = s.conf[l][q];
        if (isValid(lim, zl, cl) && hz < zl - epsAt(lim, hz)) conflict += cl;  // free space
      }
      const float fused = support - conflict;
      if (fused > best_conf) {
        best_conf = fused;
        best_depth = weighted / support;
      }
    }
    const bool keep = best_conf >= lim.min_fused_confidence;
    out_depth[x] = keep ? best_depth : kInf;
    out_conf[x] = keep ? best_conf : 0.0f;
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
    throw Error(what + ": confidence map must be CV_32FC1 of the depth map's size " + std::to_string(frame.depth.cols) +
                "x" + std::to_string(frame.depth.rows));
  }
  if (!frame.color.empty() && (frame.color.type() != CV_8UC3 || frame.color.size() != frame.depth.size())) {
    throw Error(what + ": colour image must be CV_8UC3 of the depth map's size " + std::to_string(frame.depth.cols) + "x" +
                std::to_string(frame.depth.rows));
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
    throw Error("fusion: got " + std::to_string(views.size()) + " views, fusion.num_views is " + std::to_string(n_views));
  }
  const int r = (n_views - 1) / 2;
  const DepthFrame& ref = *views[r];
  checkFusionInput(ref, {});
  const cv::Size size = ref.depth.size();
  if (static_cast<int64_t>(size.width) * size.height >= std::numeric_limits<int32_t>::max()) {
    throw Error(describe(ref) + ": image of " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                " pixels is too large (pixel indices are 32-bit)");
  }
  for (const DepthFrame* view : views) checkFusionInput(*view, size);

  FusionRowInput s;
  s.num_views = n_views;
  s.ref = r;
  s.width = size.width;
  s.height = size.height;
  s.limits.max_depth_m = static_cast<float>(std::min<double>(config.max_depth_m, std::numeric_limits<float>::max()));
  s.limits.min_confidence = std::max(static_cast<float>(config.min_input_confidence),
                                     std::numeric_limits<float>::denorm_min());
  s.limits.relative_eps = config.support_radius == SupportRadius::kRelative;
  s.limits.eps = static_cast<float>(config.eps);
  s.limits.min_fused_confidence = static_cast<float>(config.min_fused_confidence);
  const bool simd = size.width >= detail::fusionLanes();

  scratch.views.resize(n_views);
  std::array<Projector, kMaxViews> to_ref{};
  for (int v = 0; v < n_views; ++v) {
    const DepthFrame& view = *views[v];
    s.depth[v] = view.depth.ptr<float>(0);
    s.conf[v] = view.confidence.ptr<float>(0);
    s.step[v] = view.depth.step1();
    if (view.confidence.step1() != s.step[v]) {
      throw Error(describe(view) + ": depth and confidence maps must have the same row step (clone() them)");
    }
    if (v == r) continue;
    FusionScratch::View& buffers = scratch.views[v];
    buffers.storage.resize(2 * static_cast<size_t>(size.area()));  // no-op while the size stays
    buffers.depth = cv::Mat(size, CV_32FC1, buffers.storage.data());
    buffers.confidence = cv::Mat(size, CV_32FC1, buffers.storage.data() + size.area());
    buffers.row_index.resize(size.width);
    buffers.row_depth.resize(size.width);
    s.rendered_depth[v] = buffers.depth.ptr<float>(0);
    s.rendered_conf[v] = buffers.confidence.ptr<float>(0);
    s.to_view[v] = makeProjector(view, ref);
    to_ref[v] = makeProjector(ref, view);
  }

  // Step 1: one task per view, each writing only its own z-buffer.
  auto start = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < n_views - 1; ++t) {
    const int v = t < r ? t : t + 1;
    renderView(*views[v], to_ref[v], s.limits, simd, scratch.views[v]);
  }
  if (timings) timings->render_ms = msSince(start);

  // Steps 2-4: rows are independent; each output row is written by one thread.
  start = std::chrono::steady_clock::now();
  fused.depth.create(size, CV_32FC1);
  fused.confidence.create(size, CV_32FC1);
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < size.height; ++y) {
    if (simd) {
      detail::fuseRow(s, y, fused.depth.ptr<float>(y), fused.confidence.ptr<float>(y));
    } else {
      fuseRowScalar(s, y, fused.depth.ptr<float>(y), fused.confidence.ptr<float>(y));
    }
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
