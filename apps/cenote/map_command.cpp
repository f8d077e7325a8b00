// `cenote map`: build, inspect, convert and query occupancy maps (mapping/).
//   map integrate --graph scans.graph | --cloud points.ply --origin X,Y,Z  --out map.bt|.ot|.vdb
//       the job of OctoMap's graph2tree, with its options' meanings: --resolution (-res),
//       --max-range (-m; <= 0 unlimited), --sensor-model HIT MISS (-sensor), --clamping MIN MAX
//       (-clamping), --max-scans (-n). Defaults come from --config's `map:` section (5 cm, 10 m).
//   map info MAP                  resolution, bounds, voxel counts by state, memory
//   map export MAP --mesh out.ply, --points out.ply|out.pcd, --bt|--ot|--vdb out: the option names
//       the format and the extension must agree with it (mapping/io/map_file_format.h)
//   map query MAP --state X,Y,Z | --segment X,Y,Z,X,Y,Z[,RADIUS] [--stop-at-unknown]
//                 | --distance X,Y,Z [--max-distance M] | --frontiers [--position X,Y,Z]
//       distances and frontiers are computed from the whole loaded map (DistanceField::rebuild,
//       FrontierMap::rebuild) with the map: defaults of MapConfig unless given here.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "apps/cenote/commands.h"
#include "apps/cenote/subcommand.h"
#include "common/error.h"
#include "common/size_format.h"
#include "common/text_parse.h"
#include "common/yaml_section.h"
#include "mapping/distance/distance_field.h"
#include "mapping/frontier/frontier_map.h"
#include "mapping/io/map_io.h"
#include "mapping/io/scan_graph.h"
#include "mapping/query/map_query.h"
#include "io/cloud/pcd_io.h"
#include "io/cloud/ply_io.h"

namespace cenote::apps {
namespace {

using namespace cenote::mapping;

std::vector<double> parseNumbers(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::string item;
  if (!parseNumberList(text, ',', values, &item)) throw Error(option + " " + text + ": '" + item + "' is not a number");
  return values;
}

Eigen::Vector3d parsePoint(const std::string& text, const std::string& option) {
  const auto v = parseNumbers(text, option);
  if (v.size() != 3) throw Error(option + " " + text + ": expected X,Y,Z");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

struct IntegrateOptions {
  std::string graph, cloud, origin, out, config, frame_id = "world";
  double resolution = NAN, max_range = NAN;
  std::vector<double> sensor_model, clamping;
  int max_scans = -1;
};

void runIntegrate(const IntegrateOptions& o) {
  MapConfig config;
  if (!o.config.empty()) readConfigFile(o.config, "map", config);
  if (!std::isnan(o.resolution)) config.voxel_size_m = o.resolution;
  if (!std::isnan(o.max_range)) config.max_range_m = o.max_range;
  if (!o.sensor_model.empty()) {
    config.prob_hit = o.sensor_model[0];
    config.prob_miss = o.sensor_model[1];
  }
  if (!o.clamping.empty()) {
    config.clamp_min = o.clamping[0];
    config.clamp_max = o.clamping[1];
  }
  if (o.graph.empty() == o.cloud.empty()) throw Error("map integrate: give exactly one of --graph and --cloud");
  mapFormatOf(o.out);  // fail before the work on a bad extension
  OccupancyMap map(config);
  const auto t0 = std::chrono::steady_clock::now();
  size_t scans = 0, points = 0;
  double integrate_s = 0.0;
  auto add = [&](const PointBatch& batch) {
    const auto t = std::chrono::steady_clock::now();
    map.integrate(batch);
    integrate_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    ++scans;
    points += batch.size();
  };
  if (!o.graph.empty()) {
    readScanGraph(o.graph, o.max_scans, add);
  } else {
    if (o.origin.empty()) throw Error("map integrate: --cloud needs --origin X,Y,Z (the sensor position)");
    const io::PlyPoints cloud = io::readPly(o.cloud);
    PointBatch batch;
    batch.origin = parsePoint(o.origin, "--origin");
    batch.points = cloud.points;
    batch.colors = cloud.colors;
    add(batch);
  }
  saveMap(map, o.out, o.frame_id);
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const MapStats s = map.stats();
  std::printf(
      "integrated %zu scans, %zu points in %.3f s (%.1f ms/scan integrating); %llu occupied, %llu free voxels; wrote %s (%.3f s in all)\n",
      scans, points, integrate_s, scans ? 1000.0 * integrate_s / scans : 0.0, static_cast<unsigned long long>(s.occupied),
      static_cast<unsigned long long>(s.free), o.out.c_str(), total_s);
}

void printInfo(const std::string& path) {
  const auto map = loadMap(path);
  const MapStats s = map->stats();
  const MapConfig& c = map->config();
  std::printf("map %s\n  resolution: %g m\n  sensor model: hit %g, miss %g, clamping [%g, %g], occupied >= %g\n",
              path.c_str(), s.voxel_size_m, c.prob_hit, c.prob_miss, c.clamp_min, c.clamp_max, c.occupied_threshold);
  if (s.bounds.isEmpty()) {
    std::printf("  empty\n");
  } else {
    std::printf("  bounds: [%.3f, %.3f] x [%.3f, %.3f] x [%.3f, %.3f] m\n", s.bounds_m.min_m.x(), s.bounds_m.max_m.x(),
                s.bounds_m.min_m.y(), s.bounds_m.max_m.y(), s.bounds_m.min_m.z(), s.bounds_m.max_m.z());
  }
  std::printf("  voxels: %llu occupied, %llu free, %llu unknown within the bounds\n  memory: %s\n",
              static_cast<unsigned long long>(s.occupied), static_cast<unsigned long long>(s.free),
              static_cast<unsigned long long>(s.unknown_in_bounds),
              formatBytes(static_cast<double>(s.memory_bytes)).c_str());
}

struct ExportOptions {
  std::string map, mesh, points, bt, ot, vdb;
};

// The format of one export option's file: the option's, which the extension must agree with.
// --points takes PLY or PCD, as the extension says.
MapFileFormat exportFormat(const std::string& option, const std::string& path, MapFileFormat format) {
  try {
    if (format == MapFileFormat::kPointsPly && mapFileFormatOf(path) == MapFileFormat::kPointsPcd)
      return MapFileFormat::kPointsPcd;
    return resolveMapFileFormat(path, format);
  } catch (const Error& e) {
    throw Error(option + " " + path + ": " + e.what());
  }
}

void runExport(const ExportOptions& o) {
  const std::pair<const char*, MapFileFormat> kinds[] = {{"--mesh", MapFileFormat::kMeshPly},
                                                         {"--points", MapFileFormat::kPointsPly},
                                                         {"--bt", MapFileFormat::kBt},
                                                         {"--ot", MapFileFormat::kOt},
                                                         {"--vdb", MapFileFormat::kVdb}};
  const std::string* paths[] = {&o.mesh, &o.points, &o.bt, &o.ot, &o.vdb};
  std::vector<std::pair<std::string, MapFileFormat>> outputs;
  for (size_t i = 0; i < std::size(kinds); ++i) {
    if (!paths[i]->empty()) outputs.emplace_back(*paths[i], exportFormat(kinds[i].first, *paths[i], kinds[i].second));
  }
  if (outputs.empty()) throw Error("map export: give at least one of --mesh, --points, --bt, --ot, --vdb");
  const auto map = loadMap(o.map);  // after the checks: a bad name fails before the load
  for (const auto& [path, format] : outputs) {
    switch (format) {
      case MapFileFormat::kMeshPly: {
        const MeshStats m = exportMeshPly(*map, path);
        std::printf("wrote %s: %zu vertices, %zu triangles\n", path.c_str(), m.vertices, m.triangles);
        break;
      }
      case MapFileFormat::kPointsPly:
        std::printf("wrote %s: %zu occupied voxel centres\n", path.c_str(), exportOccupiedPointsPly(*map, path));
        break;
      case MapFileFormat::kPointsPcd: {
        const PointBatch centres = occupiedVoxelCentres(*map);
        io::writePcd(path, centres.points, centres.colors);
        std::printf("wrote %s: %zu occupied voxel centres\n", path.c_str(), centres.size());
        break;
      }
      default: saveMap(*map, path); std::printf("wrote %s\n", path.c_str());
    }
  }
}

struct QueryOptions {
  std::string map;
  std::vector<std::string> states, segments, distances;
  bool stop_at_unknown = false;
  bool frontiers = false;
  std::string position = "0,0,0";
  double max_distance_m = MapConfig{}.max_distance_m;
  int frontier_min_voxels = MapConfig{}.frontier_min_voxels;
  double frontier_max_extent_m = MapConfig{}.frontier_max_extent_m;
};

void printDistances(const OccupancyMap& map, const QueryOptions& o) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& s : o.distances) points.push_back(parsePoint(s, "--distance"));
  DistanceField field(map);
  field.rebuild();
  const auto results = field.query(points);
  for (size_t i = 0; i < points.size(); ++i) {
    const DistanceQuery& d = results[i];
    if (!d.within_max) {
      std::printf("distance %s: beyond %.3f m (no occupied voxel nearer)\n", o.distances[i].c_str(), d.distance_m);
    } else {
      std::printf("distance %s: %.3f m, gradient %.3f,%.3f,%.3f\n", o.distances[i].c_str(), d.distance_m, d.gradient.x(),
                  d.gradient.y(), d.gradient.z());
    }
  }
}

void printFrontiers(const OccupancyMap& map, const QueryOptions& o) {
  const Eigen::Vector3d position = parsePoint(o.position, "--position");
  FrontierMap frontiers(map);
  frontiers.rebuild();
  const auto clusters = frontiers.clusters(position);
  std::printf("frontiers: %zu clusters (%zu frontier voxels), nearest first from %s\n", clusters.size(),
              frontiers.numFrontierVoxels(), o.position.c_str());
  for (const FrontierCluster& c : clusters) {
    std::printf("frontier %llu: %zu voxels, centroid %.3f,%.3f,%.3f, distance %.3f m, box %.3f,%.3f,%.3f - %.3f,%.3f,%.3f, "
                "direction %.3f,%.3f,%.3f\n",
                static_cast<unsigned long long>(c.id), c.num_voxels, c.centroid_m.x(), c.centroid_m.y(), c.centroid_m.z(),
                c.distance_m, c.bounds_m.min_m.x(), c.bounds_m.min_m.y(), c.bounds_m.min_m.z(), c.bounds_m.max_m.x(),
                c.bounds_m.max_m.y(), c.bounds_m.max_m.z(), c.direction.x(), c.direction.y(), c.direction.z());
  }
}

void runQuery(const QueryOptions& o) {
  if (o.states.empty() && o.segments.empty() && o.distances.empty() && !o.frontiers) {
    throw Error("map query: give --state, --segment, --distance or --frontiers");
  }
  // The distance field's and frontiers' settings are not stored in map files: they come from here.
  MapConfig defaults;
  defaults.max_distance_m = o.max_distance_m;
  defaults.frontier_min_voxels = o.frontier_min_voxels;
  defaults.frontier_max_extent_m = o.frontier_max_extent_m;
  const auto map = loadMap(o.map, defaults);
  std::vector<Eigen::Vector3d> points;
  for (const auto& s : o.states) points.push_back(parsePoint(s, "--state"));
  const auto states = queryVoxels(*map, points);
  for (size_t i = 0; i < points.size(); ++i) {
    std::printf("state %s: %s (p = %.4f)\n", o.states[i].c_str(), toString(states[i].state), states[i].probability);
  }
  std::vector<SegmentQuery> segments;
  for (const auto& s : o.segments) {
    const auto v = parseNumbers(s, "--segment");
    if (v.size() != 6 && v.size() != 7) throw Error("--segment " + s + ": expected X,Y,Z,X,Y,Z[,RADIUS]");
    segments.push_back({Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]), v.size() == 7 ? v[6] : 0.0});
  }
  const auto results = checkSegments(*map, segments, o.stop_at_unknown);
  for (size_t i = 0; i < segments.size(); ++i) {
    const CollisionResult& r = results[i];
    std::printf("segment %s: %s", o.segments[i].c_str(),
                r.hit ? "hit" : (r.stopped_at_unknown ? "stopped at unknown" : "clear"));
    if (r.hit) {
      const Eigen::Vector3d c = map->toPoint(r.hit_voxel);
      std::printf(" at %.3f m (voxel centre %.3f,%.3f,%.3f)", r.hit_distance_m, c.x(), c.y(), c.z());
    }
    if (r.crossed_unknown) std::printf("; unknown from %.3f m", r.unknown_distance_m);
    std::printf("\n");
  }
  if (!o.distances.empty()) printDistances(*map, o);
  if (o.frontiers) printFrontiers(*map, o);
}

}  // namespace

void registerMapCommand(CLI::App& app) {
  CLI::App* map = app.add_subcommand("map", "Build, inspect, convert and query occupancy maps");
  map->require_subcommand(1);

  const auto [in, integrate] = addSubcommand<IntegrateOptions>(
      *map, "integrate", "Integrate OctoMap scan graphs or a point cloud (as graph2tree)", runIntegrate);
  in->add_option("--graph", integrate->graph, "OctoMap ScanGraph (.graph): scans with poses");
  in->add_option("--cloud", integrate->cloud, "one point cloud in world coordinates (binary PLY, x y z r g b)");
  in->add_option("--origin", integrate->origin, "sensor position X,Y,Z of --cloud");
  in->add_option("--resolution,--res", integrate->resolution, "voxel size in metres (graph2tree -res)");
  in->add_option("--max-range,-m", integrate->max_range, "maximum range in metres, <= 0: unlimited (graph2tree -m)");
  in->add_option("--sensor-model", integrate->sensor_model, "HIT MISS probabilities (graph2tree -sensor)")->expected(2);
  in->add_option("--clamping", integrate->clamping, "MIN MAX probabilities (graph2tree -clamping)")->expected(2);
  in->add_option("--max-scans,-n", integrate->max_scans, "integrate at most this many scans (graph2tree -n)");
  in->add_option("--config", integrate->config, "YAML file with a map: section (defaults: config/default.yaml's values)");
  in->add_option("--frame-id", integrate->frame_id, "frame name stored in .vdb metadata");
  in->add_option("--out,-o", integrate->out, "output map: .bt, .ot or .vdb")->required();

  const auto [info, info_path] = addSubcommand<std::string>(
      *map, "info", "Resolution, bounds, voxel counts and memory of a map", printInfo);
  info->add_option("map", *info_path, "map file (.vdb, .bt, .ot)")->required();

  const auto [exp, ex] = addSubcommand<ExportOptions>(
      *map, "export", "Convert a map: mesh or voxel PLY, voxel PCD, .bt, .ot, .vdb", runExport);
  exp->add_option("map", ex->map, "map file (.vdb, .bt, .ot)")->required();
  exp->add_option("--mesh", ex->mesh, "triangle mesh of occupied space, PLY with vertex colours (.ply, .mesh.ply)");
  exp->add_option("--points", ex->points,
                  "occupied voxel centres with colours: PLY (.ply, .points.ply) or PCL's PCD (.pcd)");
  exp->add_option("--bt", ex->bt, "OctoMap binary tree (.bt)");
  exp->add_option("--ot", ex->ot, "OctoMap colour tree (.ot)");
  exp->add_option("--vdb", ex->vdb, "OpenVDB file (.vdb)");

  const auto [query, q] = addSubcommand<QueryOptions>(
      *map, "query", "Voxel states, segment collisions, distances and frontiers", runQuery);
  query->add_option("map", q->map, "map file (.vdb, .bt, .ot)")->required();
  query->add_option("--state", q->states, "X,Y,Z: state and probability of the voxel (repeatable)");
  query->add_option("--segment", q->segments, "X,Y,Z,X,Y,Z[,RADIUS]: first occupied voxel (repeatable)");
  query->add_flag("--stop-at-unknown", q->stop_at_unknown, "segments end at the first unknown voxel");
  query->add_option("--distance", q->distances,
                    "X,Y,Z: distance to the nearest occupied voxel, with gradient (repeatable)");
  query->add_option("--max-distance", q->max_distance_m,
                    "distance field's maximum distance in metres (map.max_distance_m)");
  query->add_flag("--frontiers", q->frontiers, "frontier clusters: free voxels next to unknown, nearest first");
  query->add_option("--position", q->position, "X,Y,Z: position the frontiers are sorted by (default 0,0,0)");
  query->add_option("--frontier-min-voxels", q->frontier_min_voxels, "smaller frontier clusters are dropped");
  query->add_option("--frontier-max-extent", q->frontier_max_extent_m, "larger frontier clusters are split (metres)");
}

}  // namespace cenote::apps
