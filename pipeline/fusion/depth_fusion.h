// depth_fusion.h: visibility-based fusion of N_f depth maps into the middle (reference) view, after
// Merrell et al. (ICCV 2007) and Hu & Mordohai (2012), as used by Wang et al. (ICRA 2023, Sec. III-D).
//
// Units: depths in metres along each camera's optical axis, pixels, confidences as given.
// Frames: each view carries K (pinhole, pixels) and T_world_cam; T_a_b = T_world_a^-1 * T_world_b.
// Pixel (x, y) is the centre of column x, row y; a projected point goes to its NEAREST pixel,
// (floor(u + 0.5), floor(v + 0.5)), and is dropped when that pixel is outside the image or z <= 0.
//
// The rules, exactly as implemented (views v = 0 .. N_f-1 in window order, reference r = (N_f-1)/2):
//  0. Valid input pixel of view v: 0 < Z^o_v <= max_depth_m (finite), C^o_v > 0 and
//     C^o_v >= min_input_confidence. Other pixels take no part anywhere (neither as candidate nor as
//     occluder nor as free-space evidence).
//     eps(Z) = eps * Z (SupportRadius::kRelative) or eps metres (kAbsolute).
//  1. Rendering (z-buffer, nearest wins): every valid pixel of view k != r is back-projected,
//     X = Z^o_k K_k^-1 [x y 1]^T, moved to the reference camera by T_r_k and projected to its nearest
//     pixel p. The rendered map Z_k(p), C_k(p) keeps the point of smallest depth z landing on p,
//     with its own confidence (on an exact tie, the first in row-major order of view k). The
//     reference's rendered map is its own map: Z_r = Z^o_r, C_r = C^o_r.
//     (A point covers one pixel. A 2x2 footprint fills the splatting holes but, nearest winning,
//     keeps the smallest of up to four noisy depths: on the noisy scenes of
//     tests/pipeline/fusion/fusion_window_test.cpp it made inlier depths worse than the raw map.)
//  2. Candidates of pixel p: every view v with a rendered depth Z_v(p); at most one per view.
//  3. For each candidate j, with e = eps(Z_j):
//     support    S_j = { i : |Z_i - Z_j| < e } (j itself included);
//                Z^s_j = sum_{i in S_j} C_i Z_i / sum_{i in S_j} C_i,  C_j = sum_{i in S_j} C_i.
//     occlusion  for each candidate i with Z_i < Z_j - e (i lies in front of j on the reference ray,
//                so j is occluded by i): C_j -= C_i.
//     free space for each view l other than j's own view: X_j = Z_j K_r^-1 [p 1]^T is moved into
//                view l (T_l_r) and projected: depth z_l, nearest pixel q. When q is inside view l,
//                view l's ORIGINAL pixel q is valid and z_l < Z^o_l(q) - eps(z_l) (X_j lies in front
//                of the surface view l saw, i.e. in space view l saw to be empty): C_j -= C^o_l(q).
//                For l = r this reads q = p, z_l = Z_j against the reference's own depth.
//     A difference of exactly e is neither support nor conflict.
//  4. Pixel p takes the candidate with the largest C_j (on a tie, the earliest view in the window);
//     it is kept with depth Z^s_j and confidence C_j when C_j >= min_fused_confidence (C_thres),
//     otherwise the fused pixel is +inf / 0.
//
// Threads: fuseViews() uses OpenMP. Each rendered map is written by one thread only (views are
// rendered in parallel, one task per view, so rendering uses at most N_f - 1 threads; no thread
// ever writes another's z-buffer), and the fusion step writes each output row from one thread.
// Every pixel's arithmetic (Highway SIMD kernels of fusion_kernels.h, one lane per pixel) is the
// same whatever the thread count, so the result is bit-identical for any number of threads.
// A FusionScratch must not be shared between concurrent calls.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pipeline/frame/frames.h"
#include "pipeline/fusion/fusion_config.h"

namespace cenote::pipeline {

// Working memory of fuseViews(): allocated at the first call, reused while the image size and
// N_f stay the same (no allocation per frame after that).
struct FusionScratch {
  struct View {
    cv::Mat depth;                   // CV_32F rendered depth in the reference view, +inf where none
    cv::Mat confidence;              // CV_32F confidence of the rendered point where depth is finite (else stale)
    std::vector<int32_t> row_index;  // one projected source row: target pixel or -1
    std::vector<float> row_depth;    // and its depth in the reference camera
    std::vector<float> storage;      // pixels of depth, then of confidence
  };
  std::vector<View> views;  // per view of the window; the reference's is unused
};

// Wall time of the two stages of the last fuseViews() call.
struct FusionTimings {
  double render_ms = 0.0;  // rendering the other views into the reference (step 1)
  double fuse_ms = 0.0;    // candidates, support, occlusion, free space, selection (steps 2-4)
};

// Fuses views into the middle one (rules above).
// @param views  N_f = config.num_views frames in window order, same size; depth and confidence
//               CV_32FC1 (+inf / 0 where none; 0 depth and NaN count as none too).
// @param fused  receives depth (CV_32F metres, +inf where rejected) and confidence (CV_32F, 0
//               where rejected) of the reference view; t_s, K, T_world_cam and color (a shared
//               header, not a copy) are the reference's. Its Mats are reused when already of the
//               right size and type.
// @param timings optional: filled with the stage times.
// @throws cenote::Error for an invalid config, a view count other than num_views, empty or
//         differently sized maps, wrong pixel types, a non-pinhole K or an invalid pose
//         (non-finite, non-orthonormal rotation). The message names the view and its time.
void fuseViews(std::span<const DepthFrame* const> views, const FusionConfig& config, FusionScratch& scratch,
               DepthFrame& fused, FusionTimings* timings = nullptr);

// Convenience form that allocates its working memory. Same rules and errors.
DepthFrame fuseViews(const std::vector<DepthFrame>& views, const FusionConfig& config);

// @throws cenote::Error when a frame cannot take part in fusion (types, sizes, K, pose); used by
// fuseViews() and by FusionWindow::push(). `expected_size` empty: any size.
void checkFusionInput(const DepthFrame& frame, cv::Size expected_size);

}  // namespace cenote::pipeline
