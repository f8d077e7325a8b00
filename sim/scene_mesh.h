// scene_mesh.h: the simulated world as a triangle mesh, split into chunks for view culling.
// Units: metres. Frame: world (z up; the scenes put the water surface above z = 0 where it matters).
// Every triangle carries a material (which base colour the texture modulates); the mesh is the
// ground truth of the simulator: rendered depth lies exactly on it.
// Winding: every triangle's normal (v1 - v0) x (v2 - v0) points to the side a camera may see it
// from (the rasteriser draws only that side); addGrid's normal is d/di x d/dj of the position.
// Threads: a SceneMesh is built once (MeshBuilder) and then immutable; share it freely. addGrid
// evaluates its position and material functions on OpenMP threads: they must be pure.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace cenote::sim {

enum class Material : uint8_t { kRock, kSand, kCoral, kSponge, kHull, kRust, kCount };

// The world plane a triangle's texture is projected from, by the dominant axis of its normal
// (fixed per triangle, so the texture is view-independent): texture (u, v) = (x, y), (y, z) or (x, z).
enum class TexturePlane : uint8_t { kXY, kYZ, kXZ };
TexturePlane texturePlane(const Eigen::Vector3f& normal);

// A run of triangles whose vertices lie in one contiguous vertex range, with a bounding sphere.
struct MeshChunk {
  uint32_t first_vertex = 0, num_vertices = 0;
  uint32_t first_triangle = 0, num_triangles = 0;
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  float radius_m = 0.0f;
};

struct SceneMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;  // indices into vertices
  std::vector<Material> materials;                 // one per triangle
  std::vector<Eigen::Vector3f> normals;            // unit, one per triangle (winding order)
  // Per triangle 4 * material + texture plane, one int32 each: what the SIMD shader gathers.
  std::vector<int32_t> shading_codes;
  std::vector<MeshChunk> chunks;

  size_t numTriangles() const { return triangles.size(); }
  // Bounds of all vertices.
  Eigen::Vector3f minCorner() const;
  Eigen::Vector3f maxCorner() const;
};

// Appends geometry chunk by chunk; finish() computes normals and chunk bounds.
class MeshBuilder {
 public:
  // A grid of (nu + 1) x (nv + 1) vertices position(i, j), i in [0, nu], j in [0, nv], cut into chunks
  // of at most `chunk_cells` x `chunk_cells` cells; vertices on chunk borders are evaluated once per
  // chunk with the same (i, j), so neighbouring chunks meet exactly. Each cell is two triangles.
  // wrap_u: column nu is column 0 (a closed tube); material(i, j) of cell (i, j).
  void addGrid(int nu, int nv, const std::function<Eigen::Vector3d(int, int)>& position,
               const std::function<Material(int, int)>& material, bool wrap_u = false, int chunk_cells = 24);

  // A planar convex polygon (vertices in order) as a fan, in one chunk.
  void addConvexPolygon(const std::vector<Eigen::Vector3d>& polygon, Material material);

  // A quad a-b-c-d subdivided into cells of at most `cell_m` (keeps triangles small for culling).
  void addQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d,
               Material material, double cell_m);

  // Closed box from corner `origin` along three edge vectors, subdivided as addQuad.
  void addBox(const Eigen::Vector3d& origin, const Eigen::Vector3d& ex, const Eigen::Vector3d& ey,
              const Eigen::Vector3d& ez, Material material, double cell_m);

  // @throws cenote::Error when the mesh is empty or has a degenerate (zero-area) triangle.
  SceneMesh finish();

 private:
  // A chunk of the given vertex and triangle ranges (none when it has no triangle).
  void addChunk(uint32_t first_vertex, uint32_t num_vertices, uint32_t first_triangle, uint32_t num_triangles);
  SceneMesh mesh_;
};

// Distance from p to the nearest triangle of the mesh, searched only within max_distance_m
// (chunks farther away are skipped); +inf when nothing is that close.
double distanceToMesh(const SceneMesh& mesh, const Eigen::Vector3d& p, double max_distance_m);

// Distance from p to triangle (a, b, c).
double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c);

}  // namespace cenote::sim
