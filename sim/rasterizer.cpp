#include "sim/rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <omp.h>
#include <vector>

#include "common/error.h"

namespace cenote::sim {
namespace {

constexpr int kBands = 24;  // fixed work split of the image rows (not the thread count)
constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr double kMaxDepth = std::numeric_limits<double>::max();  // z <= this: finite (and not NaN)
constexpr int kNarrowRowPixels = 4;  // triangles at most this wide are drawn without a branch per pixel

// One screen-space triangle to draw, with the inverse-depth plane of its mesh triangle.
struct RasterTriangle {
  double x[3], y[3];
  double a, b, c;    // 1 / Z = a x + b y + c
  int32_t triangle;  // mesh index
};

// Buffers of one rasterize() call, kept per thread so that their pages are reused.
struct Scratch {
  std::vector<std::vector<RasterTriangle>> per_chunk;
  std::vector<std::vector<const RasterTriangle*>> bands;  // into per_chunk, in mesh order
};

// Camera-frame position and pixel position (meaningful at z >= near) of each vertex of a chunk:
// computed once per vertex instead of once per triangle corner.
struct ChunkProjection {
  std::vector<Eigen::Vector3d> cam_vertices;
  std::vector<Eigen::Vector2d> screen;
  void project(const SceneMesh& mesh, const MeshChunk& chunk, const Eigen::Matrix3d& R_cam_world,
               const Eigen::Vector3d& t_cam_world, const PinholeCamera& cam) {
    cam_vertices.resize(chunk.num_vertices);
    screen.resize(chunk.num_vertices);
    for (uint32_t v = 0; v < chunk.num_vertices; ++v) {
      const Eigen::Vector3d p = R_cam_world * mesh.vertices[chunk.first_vertex + v].cast<double>() + t_cam_world;
      cam_vertices[v] = p;
      screen[v] = Eigen::Vector2d(cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy);
    }
  }
};

struct Plane {
  Eigen::Vector3d n;
  double d;
};

// Clips polygon `in` (camera frame) to z >= near; returns the vertex count (<= 4 for a triangle).
int clipNear(const std::array<Eigen::Vector3d, 3>& in, double near, std::array<Eigen::Vector3d, 4>& out) {
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& a = in[i];
    const Eigen::Vector3d& b = in[(i + 1) % 3];
    const bool a_in = a.z() >= near, b_in = b.z() >= near;
    if (a_in) out[count++] = a;
    if (a_in != b_in) {
      const double t = (near - a.z()) / (b.z() - a.z());
      out[count++] = a + t * (b - a);
    }
  }
  return count;
}

// cam_vertices, screen: the chunk's ChunkProjection.
// Writes the triangle's screen-space pieces (none when culled, two when the near plane cuts a
// corner off) to `out`; @return how many.
int setupTriangle(const SceneMesh& mesh, uint32_t t, const std::vector<Eigen::Vector3d>& cam_vertices,
                  const std::vector<Eigen::Vector2d>& screen, uint32_t first_vertex, const PinholeCamera& cam, double near,
                  RasterTriangle out[2]) {
  const auto& tri = mesh.triangles[t];
  const uint32_t i[3] = {tri[0] - first_vertex, tri[1] - first_vertex, tri[2] - first_vertex};
  const std::array<Eigen::Vector3d, 3> v = {cam_vertices[i[0]], cam_vertices[i[1]], cam_vertices[i[2]]};
  const bool all_in = v[0].z() >= near && v[1].z() >= near && v[2].z() >= near;
  if (!all_in && v[0].z() < near && v[1].z() < near && v[2].z() < near) return 0;
  double px[4], py[4];
  int count = 3;
  if (all_in) {
    for (int k = 0; k < 3; ++k) {
      px[k] = screen[i[k]].x();
      py[k] = screen[i[k]].y();
    }
  } else {
    std::array<Eigen::Vector3d, 4> poly;
    count = clipNear(v, near, poly);
    if (count < 3) return 0;
    for (int k = 0; k < count; ++k) {
      px[k] = cam.fx * poly[k].x() / poly[k].z() + cam.cx;
      py[k] = cam.fy * poly[k].y() / poly[k].z() + cam.cy;
    }
  }
  // Rejected before the plane: off the image (the usual case in a chunk at the edge of the view),
  // or no pixel centre within the bounds (smaller than a pixel, between centres), which
  // drawTriangle would skip anyway.
  const double min_x = *std::min_element(px, px + count), max_x = *std::max_element(px, px + count);
  const double min_y = *std::min_element(py, py + count), max_y = *std::max_element(py, py + count);
  if (max_x < 0 || max_y < 0 || min_x > cam.width - 1 || min_y > cam.height - 1) return 0;
  if (std::ceil(min_x) > std::floor(max_x) || std::ceil(min_y) > std::floor(max_y)) return 0;
  Plane plane{(v[1] - v[0]).cross(v[2] - v[0]), 0.0};
  plane.d = plane.n.dot(v[0]);
  // Seen from behind (the winding's normal points away from the camera: d > 0), or edge-on (the
  // plane passes through the optical centre): covers no pixel.
  if (!(plane.d < 0.0 && plane.d * plane.d > 1e-24 * plane.n.squaredNorm())) return 0;
  plane.n = -plane.n;
  plane.d = -plane.d;
  RasterTriangle r;
  const double inverse_d = 1.0 / plane.d;  // one division per triangle
  r.a = plane.n.x() * inverse_d / cam.fx;
  r.b = plane.n.y() * inverse_d / cam.fy;
  r.c = plane.n.z() * inverse_d - r.a * cam.cx - r.b * cam.cy;
  r.triangle = static_cast<int32_t>(t);
  for (int k = 1; k + 1 < count; ++k) {  // fan
    const int idx[3] = {0, k, k + 1};
    for (int i = 0; i < 3; ++i) {
      r.x[i] = px[idx[i]];
      r.y[i] = py[idx[i]];
    }
    out[k - 1] = r;
  }
  return count - 2;
}

// Bits of `old` where keep has ones, of `value` where it has zeros.
inline float select(uint32_t keep, float old, float value) {
  uint32_t a, b;
  std::memcpy(&a, &old, sizeof(a));
  std::memcpy(&b, &value, sizeof(b));
  const uint32_t bits = (a & keep) | (b & ~keep);
  float out;
  std::memcpy(&out, &bits, sizeof(out));
  return out;
}

// Exact depth of `tri` at pixel (px, py) (double, from the inverse-depth plane); +inf where the
// plane gives none.
inline float depthAt(const RasterTriangle& tri, int px, int py) {
  const double z = 1.0 / (tri.a * px + tri.b * py + tri.c);
  return z > 0 && z <= kMaxDepth ? static_cast<float>(z) : kInfinity;
}

// Edge functions of a triangle with positive area: edge i runs from vertex i to vertex i + 1 and
// e_i(x, y) = e0 + ey y + ex x; inside is e >= -tol (a hair outside the edge, so that rounding
// never opens a crack between neighbours; the z-test settles the overlap).
struct Edges {
  double ex[3], ey[3], e0[3], tol[3];
};

// The pixels of rows [y_begin, y_end] x [x_begin, x_end] inside `tri` and nearer than the
// inverse-depth buffer take its index and depth. kBranchless: no branch per pixel, the depth
// divided out for every pixel (on rows of a few pixels, which pixels pass is unpredictable and a
// mispredicted branch costs more); otherwise a branch, and the division for winners only (on
// wide rows inside and outside come in long, predictable runs). Both give the same values.
template <bool kBranchless>
void drawRows(const RasterTriangle& tri, const Edges& edges, int y_begin, int y_end, int x_begin, int x_end, int row0,
              int width, float* inv_depth, int32_t* ids, float* depth) {
  const double* ex = edges.ex;
  const double* tol = edges.tol;
  for (int py = y_begin; py <= y_end; ++py) {
    const size_t row = static_cast<size_t>(py - row0) * width;
    float* inv_depth_row = inv_depth + row;
    int32_t* id_row = ids + row;
    float* depth_row = depth + row;
    double e[3];
    for (int i = 0; i < 3; ++i) e[i] = edges.e0[i] + edges.ey[i] * py + ex[i] * x_begin;
    const double z_row = tri.b * py + tri.c;
    for (int px = x_begin; px <= x_end; ++px) {
      const auto inv_z = static_cast<float>(tri.a * px + z_row);
      const bool inside = (e[0] >= -tol[0]) & (e[1] >= -tol[1]) & (e[2] >= -tol[2]);
      const bool wins = inside & (inv_z > inv_depth_row[px]);
      if constexpr (kBranchless) {
        const float depth_m = depthAt(tri, px, py);
        const uint32_t keep = wins ? 0u : ~0u;  // bit masks: stores the compiler cannot turn into a branch
        inv_depth_row[px] = select(keep, inv_depth_row[px], inv_z);
        depth_row[px] = select(keep, depth_row[px], depth_m);
        id_row[px] = static_cast<int32_t>((static_cast<uint32_t>(id_row[px]) & keep) |
                                          (static_cast<uint32_t>(tri.triangle) & ~keep));
      } else if (wins) {
        inv_depth_row[px] = inv_z;
        id_row[px] = tri.triangle;
        depth_row[px] = depthAt(tri, px, py);
      }
      e[0] += ex[0];
      e[1] += ex[1];
      e[2] += ex[2];
    }
  }
}

// Draws `tri` into rows [row0, row1): the z-test on the band's inverse-depth buffer (row-major,
// `width` wide, row0 first); a pixel the triangle wins gets its mesh index and its exact depth
// in `ids` and `depth` (same layout), so nothing needs to look the winner up again.
void drawTriangle(const RasterTriangle& tri, int row0, int row1, int width, float* inv_depth, int32_t* ids, float* depth) {
  double x[3] = {tri.x[0], tri.x[1], tri.x[2]}, y[3] = {tri.y[0], tri.y[1], tri.y[2]};
  const double area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
  if (area == 0.0 || !std::isfinite(area)) return;
  if (area < 0) {
    std::swap(x[1], x[2]);
    std::swap(y[1], y[2]);
  }
  const int y_begin = std::max(row0, static_cast<int>(std::ceil(std::min({y[0], y[1], y[2]}))));
  const int y_end = std::min(row1 - 1, static_cast<int>(std::floor(std::max({y[0], y[1], y[2]}))));
  const int x_begin = std::max(0, static_cast<int>(std::ceil(std::min({x[0], x[1], x[2]}))));
  const int x_end = std::min(width - 1, static_cast<int>(std::floor(std::max({x[0], x[1], x[2]}))));
  if (y_begin > y_end || x_begin > x_end) return;
  Edges edges;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    edges.ex[i] = -(y[j] - y[i]);
    edges.ey[i] = x[j] - x[i];
    edges.e0[i] = -(edges.ex[i] * x[i] + edges.ey[i] * y[i]);
    edges.tol[i] = 1e-7 * (std::abs(edges.ex[i]) + std::abs(edges.ey[i]));
  }
  if (x_end - x_begin < kNarrowRowPixels) {
    drawRows<true>(tri, edges, y_begin, y_end, x_begin, x_end, row0, width, inv_depth, ids, depth);
  } else {
    drawRows<false>(tri, edges, y_begin, y_end, x_begin, x_end, row0, width, inv_depth, ids, depth);
  }
}

}  // namespace

VisibilityBuffer rasterize(const SceneMesh& mesh, const PinholeCamera& cam, const Eigen::Isometry3d& T_world_cam,
                           double near_m) {
  if (cam.width <= 0 || cam.height <= 0) throw Error("rasterize: empty image size");
  if (!(cam.fx > 0 && cam.fy > 0)) throw Error("rasterize: focal length must be positive");
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  const Eigen::Matrix3d R = T_cam_world.linear();
  const Eigen::Vector3d t = T_cam_world.translation();

  // View-frustum culling of chunks by their bounding spheres (side planes through the optical centre).
  const std::array<Eigen::Vector3d, 4> sides = {
      Eigen::Vector3d(cam.fx, 0, cam.cx + 1).normalized(), Eigen::Vector3d(-cam.fx, 0, cam.width - cam.cx).normalized(),
      Eigen::Vector3d(0, cam.fy, cam.cy + 1).normalized(), Eigen::Vector3d(0, -cam.fy, cam.height - cam.cy).normalized()};
  std::vector<int> visible;
  for (size_t k = 0; k < mesh.chunks.size(); ++k) {
    const MeshChunk& chunk = mesh.chunks[k];
    const Eigen::Vector3d c = R * chunk.center.cast<double>() + t;
    const double r = chunk.radius_m;
    if (c.z() + r < near_m) continue;
    bool outside = false;
    for (const auto& n : sides) outside = outside || n.dot(c) < -r;
    if (!outside) visible.push_back(static_cast<int>(k));
  }

  VisibilityBuffer out;
  out.triangle.create(cam.height, cam.width, CV_32S);
  out.depth.create(cam.height, cam.width, CV_32F);
  const auto setupChunk = [&](int k, ChunkProjection& projection, auto&& emit) {
    const MeshChunk& chunk = mesh.chunks[visible[k]];
    projection.project(mesh, chunk, R, t, cam);
    RasterTriangle pieces[2];
    for (uint32_t tri = chunk.first_triangle; tri < chunk.first_triangle + chunk.num_triangles; ++tri) {
      const int n = setupTriangle(mesh, tri, projection.cam_vertices, projection.screen, chunk.first_vertex, cam, near_m,
                                  pieces);
      for (int p = 0; p < n; ++p) emit(pieces[p]);
    }
  };

  if (omp_in_parallel() || omp_get_max_threads() == 1) {
    // One thread (as when `cenote sim` renders frames on all threads): every triangle is drawn
    // as soon as it is set up, over the whole image, with no lists and no bands. The same pixels
    // as the banded path below: each pixel sees its triangles in mesh order either way, and
    // drawTriangle's arithmetic for a pixel does not depend on the rows it is given.
    static thread_local std::vector<float> inv_depth;
    inv_depth.assign(static_cast<size_t>(cam.height) * cam.width, 0.0f);
    out.triangle.setTo(-1);
    out.depth.setTo(kInfinity);
    static thread_local ChunkProjection projection;
    for (int k = 0; k < static_cast<int>(visible.size()); ++k) {
      setupChunk(k, projection, [&](const RasterTriangle& tri) {
        drawTriangle(tri, 0, cam.height, cam.width, inv_depth.data(), out.triangle.ptr<int32_t>(0),
                     out.depth.ptr<float>(0));
      });
    }
    return out;
  }

  // Triangle setup per visible chunk (in parallel), concatenated in chunk order. The lists live on
  // in per-thread scratch (about 14 MB per camera at 800x600): fresh pages for them each frame cost
  // more kernel time (page faults, zeroing) than the setup itself.
  static thread_local Scratch scratch;
  std::vector<std::vector<RasterTriangle>>& per_chunk = scratch.per_chunk;
  if (per_chunk.size() < visible.size()) per_chunk.resize(visible.size());
  for (size_t k = 0; k < visible.size(); ++k) per_chunk[k].clear();
#pragma omp parallel
  {
    ChunkProjection projection;
#pragma omp for schedule(dynamic, 4)
    for (int k = 0; k < static_cast<int>(visible.size()); ++k) {
      per_chunk[k].reserve(mesh.chunks[visible[k]].num_triangles);
      setupChunk(k, projection, [&](const RasterTriangle& tri) { per_chunk[k].push_back(tri); });
    }
  }

  // Bin into fixed bands of rows, in chunk order, so that each band sees its triangles in mesh order.
  const int band_rows = (cam.height + kBands - 1) / kBands;
  std::vector<std::vector<const RasterTriangle*>>& bands = scratch.bands;
  bands.resize(kBands);
  for (auto& band : bands) band.clear();
  for (size_t k = 0; k < visible.size(); ++k) {
    for (const RasterTriangle& tri : per_chunk[k]) {
      const double lo = std::min({tri.y[0], tri.y[1], tri.y[2]}), hi = std::max({tri.y[0], tri.y[1], tri.y[2]});
      const int y0 = std::max(0, static_cast<int>(std::ceil(lo)));
      const int y1 = std::min(cam.height - 1, static_cast<int>(std::floor(hi)));
      if (y0 > y1) continue;
      for (int b = y0 / band_rows; b <= y1 / band_rows; ++b) bands[b].push_back(&tri);
    }
  }

  // Each band is drawn by one thread straight into its rows of the output.
#pragma omp parallel
  {
    std::vector<float> inv_depth;
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < kBands; ++b) {
      const int row0 = b * band_rows, row1 = std::min(cam.height, row0 + band_rows);
      if (row0 >= row1) continue;
      inv_depth.assign(static_cast<size_t>(row1 - row0) * cam.width, 0.0f);
      cv::Mat ids = out.triangle.rowRange(row0, row1), depth = out.depth.rowRange(row0, row1);
      ids.setTo(-1);
      depth.setTo(kInfinity);
      for (const RasterTriangle* tri : bands[b]) {
        drawTriangle(*tri, row0, row1, cam.width, inv_depth.data(), ids.ptr<int32_t>(0), depth.ptr<float>(0));
      }
    }
  }
  return out;
}

}  // namespace cenote::sim
