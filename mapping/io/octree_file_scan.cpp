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

void scanBinaryNodes(NodeWalk& walk, OctreeFileSummary& s) {
  std::vector<int> pending = {0};  // depths of the inner nodes still to read, last first
  while (!pending.empty()) {
    const int depth = pending.back();
    pending.pop_back();
    const uint64_t node = s.nodes++;
    uint8_t bits[2];
    walk.read(bits, 2, node);
    int inner[8], inner_count = 0;
    for (int child = 0; child < 8; ++child) {
      const int pair = (bits[child / 4] >> (2 * (child % 4))) & 3;
      if (pair == 0) continue;
      if (depth + 1 > kOctreeDepth) walk.tooDeep(node);
      if (pair == 3) {
        if (depth + 1 == kOctreeDepth) walk.tooDeep(node);
        inner[inner_count++] = depth + 1;
      } else {
        s.leaf_voxels += voxelsAtDepth(depth + 1);
      }
    }
    // OctoMap reads the inner children in child order: push them so the first comes off first.
    for (int i = inner_count - 1; i >= 0; --i) pending.push_back(inner[i]);
  }
}

void scanFullNodes(NodeWalk& walk, OctreeFileSummary& s, bool colour) {
  std::vector<int> pending = {0};
  while (!pending.empty()) {
    const int depth = pending.back();
    pending.pop_back();
    const uint64_t node = s.nodes++;
    uint8_t value[7];
    walk.read(value, colour ? 7 : 4, node);
    float log_odds = 0.0f;
    std::memcpy(&log_odds, value, sizeof(log_odds));
    if (!std::isfinite(log_odds)) walk.fail(node, "has a log-odds that is not finite");
    uint8_t children = 0;
    walk.read(&children, 1, node);
    if (children == 0) {
      s.leaf_voxels += voxelsAtDepth(depth);
      continue;
    }
    if (depth == kOctreeDepth) walk.tooDeep(node);
    for (int child = 7; child >= 0; --child) {
      if ((children >> child) & 1) pending.push_back(depth + 1);
    }
  }
}

}  // namespace

OctreeFileSummary scanOctreeFile(const std::string& path, bool binary) {
  if (!std::filesystem::exists(path)) throw NotFoundError("cannot read " + path + ": no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throwReadError(path);
  const uint64_t file_bytes = std::filesystem::file_size(path);
  OctreeFileSummary s = readHeader(in, path, binary);
  if (!binary && s.id != "OcTree" && s.id != "ColorOcTree") {
    throw IoError(path + ": holds an OctoMap " + s.id + ", expected OcTree or ColorOcTree");
  }
  const auto header_bytes = static_cast<uint64_t>(in.tellg());
  NodeWalk walk(in, path, file_bytes - header_bytes);
  if (s.header_size == 0) return s;  // OctoMap reads no nodes then
  if (binary) {
    scanBinaryNodes(walk, s);
  } else {
    scanFullNodes(walk, s, s.id == "ColorOcTree");
  }
  return s;
}

}  // namespace cenote::mapping
