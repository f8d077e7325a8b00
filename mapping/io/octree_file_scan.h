// octree_file_scan.h: what an OctoMap file (.bt binary tree, .ot full tree) holds, read from its
// bytes before OctoMap builds anything. OctoMap's readers trust the file: a node's child bits are
// followed to any depth (a run of 0xFF bytes recurses until the stack ends), a file cut short is
// read on from uninitialised bytes, and a pruned leaf near the root stands for up to 2^48 voxels
// that loading expands one by one (100 bytes of .bt: 10^14 voxels). This scan walks the same
// node structure, checks every node lies within the file and within OctoMap's 16 levels, and
// counts the voxels the leaves cover and the grid nodes they fill, so that a loader can refuse
// the file first. An OctoMap key maps to the voxel (key - 2^15), so an octree node at depth 13, 10
// or 6 is exactly one leaf, lower or upper inner node of the map's OpenVDB tree.
// Formats (OctoMap 1.9, AbstractOcTree.cpp and OcTreeBaseImpl.hxx):
//   header  "# Octomap OcTree binary file" (.bt) or "# Octomap OcTree file" (.ot), then lines
//           "id <type>", "size <nodes>", "res <metres>", "data".
//   .bt     per node 2 bytes, 2 bits per child: 00 none, 01 occupied leaf, 10 free leaf, 11 inner;
//           inner children follow depth-first in child order.
//   .ot     per node its value (OcTree: float log-odds; ColorOcTree: float and 3 colour bytes)
//           and 1 byte of child bits; children follow depth-first in child order.
// Threads: pure functions.
#pragma once

#include <cstdint>
#include <string>

namespace cenote::mapping {

inline constexpr int kOctreeDepth = 16;  // OctoMap's levels below the root: 2^16 voxels per axis

struct OctreeFileSummary {
  std::string id;             // "OcTree", "ColorOcTree"
  double resolution_m = 0.0;  // the header's res
  uint64_t header_size = 0;   // the header's size (OctoMap reads no nodes when 0)
  uint64_t data_offset = 0;   // the byte where the nodes begin, after the header's "data" line
  uint64_t nodes = 0;         // nodes in the data
  uint64_t leaf_voxels = 0;   // voxels the leaves cover: 8^(16 - depth) each
  // The OpenVDB nodes those voxels fill once loaded (leaves of 8^3 voxels, inner nodes of 64^3
  // and 1024^3): voxels scattered one per leaf cost far more memory than their count says.
  uint64_t grid_leaves = 0, grid_inner1 = 0, grid_inner2 = 0;

  // Bytes of the loaded log-odds grid's nodes (OpenVDB 10, float values), within a few %.
  uint64_t gridBytes() const;
};

// @param binary true for .bt, false for .ot.
// @throws cenote::Error (IoError) "<path>: ..." naming the field: a missing or foreign header line,
//   a resolution that is not finite and positive, an id other than OcTree / ColorOcTree (.ot), a
//   node beyond the end of the file, children below depth 16, a non-finite log-odds (.ot).
//   NotFoundError when the file does not exist.
OctreeFileSummary scanOctreeFile(const std::string& path, bool binary);

}  // namespace cenote::mapping
