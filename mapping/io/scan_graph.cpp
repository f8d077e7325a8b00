#include "mapping/io/scan_graph.h"

#include <octomap/ScanGraph.h>

#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace cenote::mapping {

int readScanGraph(const std::string& path, int max_scans, const std::function<void(const PointBatch&)>& visit) {
  if (!std::filesystem::is_regular_file(path)) throw NotFoundError("cannot read " + path + ": no such file");
  std::ifstream in(path, std::ios::binary);
  octomap::ScanGraph graph;
  if (!in || !graph.readBinary(in) || graph.size() == 0) {
    throw Error("cannot read " + path + ": not an OctoMap ScanGraph (.graph) file, or empty");
  }
  int count = 0;
  PointBatch batch;
  for (auto it = graph.begin(); it != graph.end(); ++it) {
    if (max_scans > 0 && count >= max_scans) break;
    const octomap::ScanNode& node = **it;
    if (node.scan == nullptr || node.scan->size() == 0) continue;
    batch.clear();
    batch.t_s = node.id;
    const octomap::point3d origin = node.pose.trans();
    batch.origin = Eigen::Vector3d(origin.x(), origin.y(), origin.z());
    batch.points.reserve(node.scan->size());
    for (size_t i = 0; i < node.scan->size(); ++i) {
      const octomap::point3d p = node.pose.transform((*node.scan)[i]);
      batch.points.emplace_back(p.x(), p.y(), p.z());
    }
    visit(batch);
    ++count;
  }
  return count;
}

}  // namespace cenote::mapping
