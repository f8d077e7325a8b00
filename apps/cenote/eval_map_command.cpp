// `cenote eval map`: occupancy agreement of two maps (.vdb of ours, OctoMap .bt / .ot), voxel by
// voxel (eval/map/map_comparison.h). Lives apart from eval_command.cpp because it needs mapping/.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "apps/cenote/commands.h"
#include "apps/cenote/subcommand.h"
#include "eval/map/map_comparison.h"
#include "eval/report/metrics_json.h"

namespace cenote::apps {
namespace {

struct MapOptions {
  std::string estimate, reference, json;
};

std::string fraction(double v) {
  if (!std::isfinite(v)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f %%", 100.0 * v);
  return text;
}

void runMap(const MapOptions& o) {
  const eval::MapComparison m = eval::compareMapFiles(o.estimate, o.reference);
  const eval::OccupancyAgreement& a = m.agreement;
  const eval::OccupancyConfusion& c = m.confusion;
  std::cout << "maps: " << o.estimate << " against " << o.reference << " (" << m.voxel_size_m << " m voxels)\n"
            << "  voxels known in either    " << a.known_either << "\n"
            << "  voxels known in both      " << a.known_both << "\n"
            << "  agreement (either)        " << fraction(a.agreement) << "\n"
            << "  agreement (both known)    " << fraction(a.known_agreement) << "\n"
            << "  agreement within a voxel  " << fraction(a.agreement_within_voxel) << "\n"
            << "  occupied IoU              " << fraction(a.occupied_iou) << "\n"
            << "  occupied precision        " << fraction(a.occupied_precision) << "\n"
            << "  occupied recall           " << fraction(a.occupied_recall) << "\n"
            << "  estimate \\ reference   unknown        free    occupied\n";
  const char* names[] = {"unknown", "free", "occupied"};
  for (int e = 0; e < 3; ++e) {
    char line[128];
    std::snprintf(line, sizeof(line), "  %-18s %10lld  %10lld  %10lld\n", names[e], static_cast<long long>(c.counts[e][0]),
                  static_cast<long long>(c.counts[e][1]), static_cast<long long>(c.counts[e][2]));
    std::cout << line;
  }
  if (!o.json.empty()) {
    eval::writeTextFile(o.json, eval::toJson(a, c, o.estimate, o.reference, m.voxel_size_m));
    std::cout << "numbers: " << o.json << "\n";
  }
}

}  // namespace

void registerEvalMapCommand(CLI::App& eval_cmd) {
  const auto [cmd, o] = addSubcommand<MapOptions>(eval_cmd, "map",
                                                  "Occupancy agreement of two maps (.vdb, OctoMap .bt / .ot)", runMap);
  cmd->add_option("--estimate", o->estimate, "Map to judge (.vdb, .bt or .ot)")->required();
  cmd->add_option("--reference", o->reference, "Reference map, same voxel size (.vdb, .bt or .ot)")->required();
  cmd->add_option("--json", o->json, "Write the numbers as JSON to this file");
}

}  // namespace cenote::apps
