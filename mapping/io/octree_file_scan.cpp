#include "mapping/io/octree_file_scan.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

#include "common/error.h"

namespace cenote::mapping {
namespace {

// The header as OctoMap's AbstractOcTree::readHeader reads it: whitespace-separated keywords up
// to "data" and the end of its line; '#' comments and unknown keywords skip their line.
OctreeFileSummary readHeader(std::istream& in, const std::string& path, bool binary) {
  const std::string expected = binary ? "# Octomap OcTree binary file" : "# Octomap OcTree file";
  std::string line;
  std::getline(in, line);
  if (line.compare(0, expected.size(), expected) != 0) {
    throw IoError(path + ": not an OctoMap " + (binary ? "binary tree (.bt)" : "tree file (.ot)") +
                  ": the first line is not '" + expected + "'");
  }
  OctreeFileSummary s;
  bool have_res = false;
  std::string token;
  while (in >> token) {
    if (token == "data") {
      in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
      if (s.id.empty()) throw IoError(path + ": OctoMap header has no id");
      if (!have_res || !std::isfinite(s.resolution_m) || s.resolution_m <= 0.0) {
        throw IoError(path + ": OctoMap header res must be a finite resolution > 0 m");
      }
      return s;
    }
    if (token == "id") {
      in >> s.id;
    } else if (token == "res") {
      have_res = static_cast<bool>(in >> s.resolution_m);
      if (!have_res) throw IoError(path + ": OctoMap header res is not a number");
    } else if (token == "size") {
      if (!(in >> s.header_size)) throw IoError(path + ": OctoMap header size is not a number");
    } else {
      in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    }
  }
  throw IoError(path + ": OctoMap header has no 'data' line");
}

uint64_t voxelsAtDepth(int depth) { return uint64_t{1} << (3 * (kOctreeDepth - depth)); }

// The OpenVDB nodes of the map's log-odds tree (Tree4<float, 4, 3, 3>, mapping/detail/map_impl.h)
// the leaves of a depth-first walk fill. A grid node of
// side 2^k voxels is one octree node at depth 16 - k: a leaf at or above that depth fills 8^(that
// depth - its depth) of them, leaves below it share their ancestor's, counted once.
class GridNodeCount {
 public:
  // A node at `depth` is entered (depth-first order: everything below it comes before the next).
  void enter(int depth) {
    for (Level& l : levels_)
      if (depth == l.depth) l.counted = false;
  }
  // A leaf at `depth`, below a node entered last at the levels above it.
  void leaf(int depth, OctreeFileSummary& s) {
    for (Level& l : levels_) {
      if (depth <= l.depth) {
        s.*l.count += uint64_t{1} << (3 * (l.depth - depth));
      } else if (!l.counted) {
        ++(s.*l.count);
        l.counted = true;
      }
    }
  }

 private:
  struct Level {
    int depth;  // of the octree nodes that are one grid node of this level
    uint64_t OctreeFileSummary::*count;
    bool counted = false;  // the current ancestor at this depth has been counted
  };
  Level levels_[3] = {{kOctreeDepth - 3, &OctreeFileSummary::grid_leaves},
                      {kOctreeDepth - 6, &OctreeFileSummary::grid_inner1},
                      {kOctreeDepth - 10, &OctreeFileSummary::grid_inner2}};
};

// Reads the nodes depth-first with an explicit stack (depth is at most 16 by the checks).
class NodeWalk {
 public:
  NodeWalk(std::istream& in, const std::string& path, uint64_t data_bytes) : in_(in), path_(path), remaining_(data_bytes) {}

  void read(void* out, uint64_t bytes, uint64_t node) {
    if (bytes > remaining_) {
      throw IoError(path_ + ": OctoMap data is truncated at node " + std::to_string(node) + " (" +
                    std::to_string(remaining_) + " bytes left of the file)");
    }
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(bytes));
    if (!in_) throw IoError(path_ + ": read failed at node " + std::to_string(node));
    remaining_ -= bytes;
  }

  [[noreturn]] void fail(uint64_t node, const std::string& what) const {
    throw IoError(path_ + ": OctoMap node " + std::to_string(node) + " " + what);
  }
  [[noreturn]] void tooDeep(uint64_t node) const {
    fail(node, "has children below depth " + std::to_string(kOctreeDepth) + ", the deepest level of a tree");
  }

 private:
  std::istream& in_;
  const std::string& path_;
  uint64_t remaining_;
};

// Reads the nodes depth-first, as OctoMap does. readNode(depth, node, leaf, inner) reads one node,
// calls leaf(depth) for each leaf it holds or is, and appends its inner children's depths to
// `inner` in child order (OctoMap reads them in that order).
template <typename ReadNode>
void walkNodes(OctreeFileSummary& s, ReadNode readNode) {
  std::vector<int> pending = {0};  // depths of the inner nodes still to read, last first
  std::vector<int> inner;
  GridNodeCount grid;
  auto leaf = [&](int depth) {
    s.leaf_voxels += voxelsAtDepth(depth);
    grid.leaf(depth, s);
  };
  while (!pending.empty()) {
    const int depth = pending.back();
    pending.pop_back();
    grid.enter(depth);
    inner.clear();
    readNode(depth, s.nodes++, leaf, inner);
    pending.insert(pending.end(), inner.rbegin(), inner.rend());
  }
}

void scanBinaryNodes(NodeWalk& walk, OctreeFileSummary& s) {
  walkNodes(s, [&](int depth, uint64_t node, auto& leaf, std::vector<int>& inner) {
    uint8_t bits[2];
    walk.read(bits, 2, node);
    // No child at all: OctoMap keeps the node as a leaf of its depth (the root: every voxel).
    if (bits[0] == 0 && bits[1] == 0) return leaf(depth);
    for (int child = 0; child < 8; ++child) {
      const int pair = (bits[child / 4] >> (2 * (child % 4))) & 3;
      if (pair == 0) continue;
      if (depth + 1 > kOctreeDepth) walk.tooDeep(node);
      if (pair == 3) {
        if (depth + 1 == kOctreeDepth) walk.tooDeep(node);
        inner.push_back(depth + 1);
      } else {
        leaf(depth + 1);
      }
    }
  });
}

void scanFullNodes(NodeWalk& walk, OctreeFileSummary& s, bool colour) {
  walkNodes(s, [&](int depth, uint64_t node, auto& leaf, std::vector<int>& inner) {
    uint8_t value[7];
    walk.read(value, colour ? 7 : 4, node);
    float log_odds = 0.0f;
    std::memcpy(&log_odds, value, sizeof(log_odds));
    if (!std::isfinite(log_odds)) walk.fail(node, "has a log-odds that is not finite");
    uint8_t children = 0;
    walk.read(&children, 1, node);
    if (children == 0) return leaf(depth);
    if (depth == kOctreeDepth) walk.tooDeep(node);
    for (int child = 0; child < 8; ++child) {
      if ((children >> child) & 1) inner.push_back(depth + 1);
    }
  });
}

}  // namespace

uint64_t OctreeFileSummary::gridBytes() const {
  // Values and masks of each node: 8^3 floats; 8^3 and 16^3 child pointers or tiles of 8 bytes.
  constexpr uint64_t kLeafBytes = 512 * 4 + 64 + 32, kInner1Bytes = 512 * 8 + 2 * 64 + 32,
                     kInner2Bytes = 4096 * 8 + 2 * 512 + 32;
  return grid_leaves * kLeafBytes + grid_inner1 * kInner1Bytes + grid_inner2 * kInner2Bytes;
}

OctreeFileSummary scanOctreeFile(const std::string& path, bool binary) {
  if (!std::filesystem::exists(path)) throw NotFoundError("cannot read " + path + ": no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throwReadError(path);
  const uint64_t file_bytes = std::filesystem::file_size(path);
  OctreeFileSummary s = readHeader(in, path, binary);
  if (!binary && s.id != "OcTree" && s.id != "ColorOcTree") {
    throw IoError(path + ": holds an OctoMap " + s.id + ", expected OcTree or ColorOcTree");
  }
  s.data_offset = static_cast<uint64_t>(in.tellg());
  NodeWalk walk(in, path, file_bytes - s.data_offset);
  if (s.header_size == 0) return s;  // OctoMap reads no nodes then
  if (binary) {
    scanBinaryNodes(walk, s);
  } else {
    scanFullNodes(walk, s, s.id == "ColorOcTree");
  }
  return s;
}

}  // namespace cenote::mapping
