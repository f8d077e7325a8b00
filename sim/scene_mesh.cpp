#include "sim/scene_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.h"

namespace cenote::sim {
namespace {

constexpr uint32_t kMinParallelVertices = 16384;  // addGrid: fewer vertices are evaluated on one thread

}  // namespace

Eigen::Vector3f SceneMesh::minCorner() const {
  Eigen::Vector3f m = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  for (const auto& v : vertices) m = m.cwiseMin(v);
  return m;
}

Eigen::Vector3f SceneMesh::maxCorner() const {
  Eigen::Vector3f m = Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity());
  for (const auto& v : vertices) m = m.cwiseMax(v);
  return m;
}

void MeshBuilder::addChunk(uint32_t first_vertex, uint32_t num_vertices, uint32_t first_triangle, uint32_t num_triangles) {
  if (num_triangles == 0) return;
  MeshChunk chunk;
  chunk.first_vertex = first_vertex;
  chunk.num_vertices = num_vertices;
  chunk.first_triangle = first_triangle;
  chunk.num_triangles = num_triangles;
  mesh_.chunks.push_back(chunk);
}

void MeshBuilder::addGrid(int nu, int nv, const std::function<Eigen::Vector3d(int, int)>& position,
                          const std::function<Material(int, int)>& material, bool wrap_u, int chunk_cells) {
  // The chunks in order and where their vertices and triangles go; then positions and materials
  // (pure functions of (i, j)) are evaluated in parallel, each chunk into its own ranges: the same
  // mesh whatever the thread count.
  struct Block {
    int ci, cj, ni, nj;
    uint32_t first_vertex, first_triangle;
  };
  std::vector<Block> blocks;
  auto num_vertices = static_cast<uint32_t>(mesh_.vertices.size());
  auto num_triangles = static_cast<uint32_t>(mesh_.triangles.size());
  const uint32_t grid_first_vertex = num_vertices;
  for (int cj = 0; cj < nv; cj += chunk_cells) {
    for (int ci = 0; ci < nu; ci += chunk_cells) {
      const int ni = std::min(chunk_cells, nu - ci), nj = std::min(chunk_cells, nv - cj);
      blocks.push_back({ci, cj, ni, nj, num_vertices, num_triangles});
      num_vertices += static_cast<uint32_t>((ni + 1) * (nj + 1));
      num_triangles += static_cast<uint32_t>(2 * ni * nj);
    }
  }
  mesh_.vertices.resize(num_vertices);
  mesh_.triangles.resize(num_triangles);
  mesh_.materials.resize(num_triangles);
  // Threads only for large grids (curved terrain and walls): a box face is a few hundred cheap
  // vertices, and a parallel region per face costs more than it saves (on a busy machine it waits
  // for a descheduled thread: the wreck's ~250 faces took 2.6 s instead of 0.4 s on 2 threads).
  const bool large = num_vertices - grid_first_vertex >= kMinParallelVertices;
#pragma omp parallel for schedule(dynamic, 1) if (large)
  for (int b = 0; b < static_cast<int>(blocks.size()); ++b) {
    const Block& block = blocks[b];
    const int ci = block.ci, cj = block.cj, ni = block.ni, nj = block.nj;
    for (int j = 0; j <= nj; ++j) {
      for (int i = 0; i <= ni; ++i) {
        const int gi = (wrap_u && ci + i == nu) ? 0 : ci + i;
        mesh_.vertices[block.first_vertex + static_cast<uint32_t>(j * (ni + 1) + i)] = position(gi, cj + j).cast<float>();
      }
    }
    auto index = [&](int i, int j) { return block.first_vertex + static_cast<uint32_t>(j * (ni + 1) + i); };
    uint32_t t = block.first_triangle;
    for (int j = 0; j < nj; ++j) {
      for (int i = 0; i < ni; ++i) {
        const Material m = material(ci + i, cj + j);
        // Alternate the diagonal so that the tessellation has no preferred direction.
        if (((ci + i) + (cj + j)) % 2 == 0) {
          mesh_.triangles[t] = {index(i, j), index(i + 1, j), index(i + 1, j + 1)};
          mesh_.triangles[t + 1] = {index(i, j), index(i + 1, j + 1), index(i, j + 1)};
        } else {
          mesh_.triangles[t] = {index(i, j), index(i + 1, j), index(i, j + 1)};
          mesh_.triangles[t + 1] = {index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)};
        }
        mesh_.materials[t] = mesh_.materials[t + 1] = m;
        t += 2;
      }
    }
  }
  for (const Block& block : blocks) {
    addChunk(block.first_vertex, static_cast<uint32_t>((block.ni + 1) * (block.nj + 1)), block.first_triangle,
             static_cast<uint32_t>(2 * block.ni * block.nj));
  }
}

void MeshBuilder::addConvexPolygon(const std::vector<Eigen::Vector3d>& polygon, Material material) {
  if (polygon.size() < 3) return;
  const auto first_vertex = static_cast<uint32_t>(mesh_.vertices.size());
  const auto first_triangle = static_cast<uint32_t>(mesh_.triangles.size());
  for (const auto& p : polygon) mesh_.vertices.push_back(p.cast<float>());
  for (uint32_t i = 1; i + 1 < polygon.size(); ++i) {
    mesh_.triangles.push_back({first_vertex, first_vertex + i, first_vertex + i + 1});
    mesh_.materials.push_back(material);
  }
  addChunk(first_vertex, static_cast<uint32_t>(polygon.size()), first_triangle, static_cast<uint32_t>(polygon.size() - 2));
}

void MeshBuilder::addQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& d, Material material, double cell_m) {
  const int nu = std::max(1, static_cast<int>(std::ceil(std::max((b - a).norm(), (c - d).norm()) / cell_m)));
  const int nv = std::max(1, static_cast<int>(std::ceil(std::max((d - a).norm(), (c - b).norm()) / cell_m)));
  addGrid(
      nu, nv,
      [&](int i, int j) {
        const double u = static_cast<double>(i) / nu, v = static_cast<double>(j) / nv;
        return Eigen::Vector3d((1 - v) * ((1 - u) * a + u * b) + v * ((1 - u) * d + u * c));
      },
      [&](int, int) { return material; });
}

void MeshBuilder::addBox(const Eigen::Vector3d& o, const Eigen::Vector3d& ex, const Eigen::Vector3d& ey,
                         const Eigen::Vector3d& ez, Material material, double cell_m) {
  const Eigen::Vector3d p000 = o, p100 = o + ex, p010 = o + ey, p110 = o + ex + ey;
  const Eigen::Vector3d p001 = o + ez, p101 = o + ex + ez, p011 = o + ey + ez, p111 = o + ex + ey + ez;
  addQuad(p000, p010, p110, p100, material, cell_m);  // bottom
  addQuad(p001, p101, p111, p011, material, cell_m);  // top
  addQuad(p000, p100, p101, p001, material, cell_m);  // -y side
  addQuad(p010, p011, p111, p110, material, cell_m);  // +y side
  addQuad(p000, p001, p011, p010, material, cell_m);  // -x side
  addQuad(p100, p110, p111, p101, material, cell_m);  // +x side
}

TexturePlane texturePlane(const Eigen::Vector3f& normal) {
  const Eigen::Vector3f a = normal.cwiseAbs();
  if (a.z() >= a.x() && a.z() >= a.y()) return TexturePlane::kXY;
  return a.x() >= a.y() ? TexturePlane::kYZ : TexturePlane::kXZ;
}

SceneMesh MeshBuilder::finish() {
  if (mesh_.triangles.empty()) throw Error("sim: the scene has no triangles");
  mesh_.normals.resize(mesh_.triangles.size());
  for (size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const auto& tri = mesh_.triangles[t];
    const Eigen::Vector3f n =
        (mesh_.vertices[tri[1]] - mesh_.vertices[tri[0]]).cross(mesh_.vertices[tri[2]] - mesh_.vertices[tri[0]]);
    if (!(n.norm() > 1e-12f)) throw Error("sim: degenerate triangle " + std::to_string(t) + " in the scene mesh");
    mesh_.normals[t] = n.normalized();
  }
  mesh_.shading_codes.resize(mesh_.triangles.size());
  for (size_t t = 0; t < mesh_.triangles.size(); ++t) {
    mesh_.shading_codes[t] = 4 * static_cast<int32_t>(mesh_.materials[t]) +
                             static_cast<int32_t>(texturePlane(mesh_.normals[t]));
  }
  for (MeshChunk& chunk : mesh_.chunks) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = Eigen::Vector3f::Constant(-1e30f);
    for (uint32_t v = chunk.first_vertex; v < chunk.first_vertex + chunk.num_vertices; ++v) {
      lo = lo.cwiseMin(mesh_.vertices[v]);
      hi = hi.cwiseMax(mesh_.vertices[v]);
    }
    chunk.center = 0.5f * (lo + hi);
    chunk.radius_m = 0.5f * (hi - lo).norm() + 1e-4f;
  }
  return std::move(mesh_);
}

double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c) {
  // Ericson, Real-Time Collision Detection, 5.1.5: closest point by Voronoi regions.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm();
  }
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

double distanceToMesh(const SceneMesh& mesh, const Eigen::Vector3d& p, double max_distance_m) {
  double best = std::numeric_limits<double>::infinity();
  for (const MeshChunk& chunk : mesh.chunks) {
    if ((p - chunk.center.cast<double>()).norm() > chunk.radius_m + max_distance_m) continue;
    for (uint32_t t = chunk.first_triangle; t < chunk.first_triangle + chunk.num_triangles; ++t) {
      const auto& tri = mesh.triangles[t];
      const double d = pointTriangleDistance(p, mesh.vertices[tri[0]].cast<double>(), mesh.vertices[tri[1]].cast<double>(),
                                             mesh.vertices[tri[2]].cast<double>());
      best = std::min(best, d);
    }
  }
  return best <= max_distance_m ? best : std::numeric_limits<double>::infinity();
}

}  // namespace cenote::sim
