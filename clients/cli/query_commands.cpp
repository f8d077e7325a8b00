// query_commands.cpp: cenote-cli's map queries.
//   state X,Y,Z [X,Y,Z ...] | --points-file F   "x y z unknown|free|occupied probability" per point
//   box MIN MAX                                  voxel counts by state in the box
//   segment START END [--radius R] [--stop-at-unknown]
//   raycast ORIGIN DIRECTION [--max-range M] [--stop-at-unknown]
//   distance X,Y,Z ... | --points-file F         "x y z distance gx gy gz" per point
//   frontiers [--from X,Y,Z] [--max N] [--region MIN MAX]
//   info                                         resolution, frame, bounds, counts, sensor model
#include <cstdio>
#include <functional>
#include <memory>
#include <tuple>

#include "clients/cli/cli_input.h"
#include "clients/cli/commands.h"

namespace cenote::cli {

namespace {

std::vector<Eigen::Vector3d> gatherPoints(const std::vector<std::string>& texts, const std::string& points_file,
                                          const char* command) {
  std::vector<Eigen::Vector3d> points;
  for (const std::string& text : texts) points.push_back(parsePoint(text, command));
  if (!points_file.empty()) {
    const auto more = readPointsFile(points_file);
    points.insert(points.end(), more.begin(), more.end());
  }
  if (points.empty()) throw CliError(std::string(command) + ": give points X,Y,Z or --points-file F");
  return points;
}

client::Box parseBox(const std::string& min_text, const std::string& max_text, const char* what) {
  const client::Box box{parsePoint(min_text, std::string(what) + " MIN"), parsePoint(max_text, std::string(what) + " MAX")};
  if (box.isEmpty()) throw CliError(std::string(what) + ": MIN must not exceed MAX on any axis");
  return box;
}

void printCollision(const client::Collision& c) {
  if (c.hit) {
    std::printf("hit at %.3f m, voxel %d,%d,%d (centre %s)", c.hit_distance_m, c.hit_voxel.x(), c.hit_voxel.y(),
                c.hit_voxel.z(), formatPoint(c.hit_point_m).c_str());
  } else if (c.stopped_at_unknown) {
    std::printf("stopped at unknown at %.3f m", c.unknown_distance_m);
  } else {
    std::printf("clear");
  }
  if (c.crossed_unknown && !c.stopped_at_unknown) std::printf("; unknown from %.3f m", c.unknown_distance_m);
  std::printf("\n");
}

// A command about points (state, distance): X,Y,Z arguments and the points of --points-file F, in that
// order (gatherPoints), handed to `answer`.
void registerPointsCommand(CLI::App& app, const char* name, const std::string& description, const char* points_help,
                           std::function<void(const std::vector<Eigen::Vector3d>&)> answer) {
  struct Options {
    std::vector<std::string> points;
    std::string points_file;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(name, description);
  cmd->add_option("points", o->points, points_help);
  cmd->add_option("--points-file", o->points_file, "File of points, one 'x y z' a line");
  cmd->callback([o, name, answer] { answer(gatherPoints(o->points, o->points_file, name)); });
}

void registerState(CLI::App& app, Connection& connection) {
  const auto print_states = [&connection](const std::vector<Eigen::Vector3d>& points) {
    const auto results = connection.client().voxels(points);
    for (size_t i = 0; i < points.size(); ++i) {
      std::printf("%s %s %.4f\n", formatPointSpaced(points[i]).c_str(), client::toString(results[i].state),
                  results[i].probability);
    }
  };
  registerPointsCommand(app, "state", "State and occupancy probability of the voxel at each point",
                        "X,Y,Z points (metres, world frame)", print_states);
}

void registerBox(CLI::App& app, Connection& connection) {
  struct Options {
    std::string min, max;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("box", "Voxel counts by state in an axis-aligned box (voxel centres inside)");
  cmd->add_option("min", o->min, "X,Y,Z lower corner")->required();
  cmd->add_option("max", o->max, "X,Y,Z upper corner")->required();
  cmd->callback([o, &connection] {
    const auto counts = connection.client().boxes({parseBox(o->min, o->max, "box")}).front();
    std::printf("occupied %llu free %llu unknown %llu\n", static_cast<unsigned long long>(counts.occupied),
                static_cast<unsigned long long>(counts.free), static_cast<unsigned long long>(counts.unknown));
  });
}

// The options of a collision query: two points (START END, or ORIGIN DIRECTION), its one number
// (radius, or maximum range) and --stop-at-unknown.
struct CollisionOptions {
  std::string first, second;
  double number = 0.0;
  bool stop_at_unknown = false;
};

// What names a collision query's subcommand and its options.
struct CollisionCommand {
  const char* name;
  const char* help;
  const char* first;        // the first point's name ("X,Y,Z")
  const char* second;       // the second point's name
  const char* second_help;  // what the second point is
  const char* number;       // the number's option
  const char* number_help;
};

// The subcommand of a collision query with its options in help order (two required points, the
// number's option, which is returned to give it more, then --stop-at-unknown); the caller adds the
// callback.
std::tuple<CLI::App*, std::shared_ptr<CollisionOptions>, CLI::Option*> addCollisionCommand(CLI::App& app,
                                                                                           const CollisionCommand& c,
                                                                                           double number) {
  auto o = std::make_shared<CollisionOptions>();
  o->number = number;
  CLI::App* cmd = app.add_subcommand(c.name, c.help);
  cmd->add_option(c.first, o->first, "X,Y,Z")->required();
  cmd->add_option(c.second, o->second, c.second_help)->required();
  CLI::Option* number_option = cmd->add_option(c.number, o->number, c.number_help);
  cmd->add_flag("--stop-at-unknown", o->stop_at_unknown, "Unknown voxels are not free to pass");
  return {cmd, o, number_option};
}

void registerSegment(CLI::App& app, Connection& connection) {
  const auto [cmd, o, radius] = addCollisionCommand(
      app,
      {"segment", "First occupied voxel along a segment (or a capsule with --radius)", "start", "end", "X,Y,Z", "--radius",
       "Capsule radius, metres (0: the voxels the segment passes through)"},
      0.0);
  cmd->callback([o = o, &connection] {
    const client::Segment segment{parsePoint(o->first, "segment START"), parsePoint(o->second, "segment END"), o->number};
    printCollision(connection.client().segment(segment, o->stop_at_unknown));
  });
}

void registerRaycast(CLI::App& app, Connection& connection) {
  const auto [cmd, o, max_range] = addCollisionCommand(
      app,
      {"raycast", "First occupied voxel along a ray", "origin", "direction", "DX,DY,DZ (any non-zero length)",
       "--max-range", "Metres"},
      10.0);
  max_range->capture_default_str();
  cmd->callback([o = o, &connection] {
    const client::Ray ray{parsePoint(o->first, "raycast ORIGIN"), parsePoint(o->second, "raycast DIRECTION")};
    printCollision(connection.client().raycast({ray}, o->number, o->stop_at_unknown).front());
  });
}

void registerDistance(CLI::App& app, Connection& connection) {
  const auto print_distances = [&connection](const std::vector<Eigen::Vector3d>& points) {
    const auto results = connection.client().distances(points);
    for (size_t i = 0; i < points.size(); ++i) {
      const auto& r = results[i];
      std::printf("%s %.4f %.4f %.4f %.4f%s\n", formatPointSpaced(points[i]).c_str(), r.distance_m, r.gradient.x(),
                  r.gradient.y(), r.gradient.z(), r.within_max ? "" : " beyond-max");
    }
  };
  registerPointsCommand(app, "distance",
                        "Distance to the nearest occupied voxel and its gradient: 'x y z distance gx gy gz' per point",
                        "X,Y,Z points", print_distances);
}

void registerFrontiers(CLI::App& app, Connection& connection) {
  struct Options {
    std::string from = "0,0,0";
    unsigned max_clusters = 0;
    std::vector<std::string> region;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("frontiers", "Frontier clusters (free next to unknown), nearest first");
  cmd->add_option("--from", o->from, "X,Y,Z: sort by distance from here")->capture_default_str();
  cmd->add_option("--max", o->max_clusters, "At most this many clusters (0: all)");
  cmd->add_option("--region", o->region, "MIN MAX: only clusters whose centroid lies in this box")->expected(2);
  cmd->callback([o, &connection] {
    client::FrontierQuery query;
    query.position_m = parsePoint(o->from, "--from");
    query.max_clusters = o->max_clusters;
    if (!o->region.empty()) query.region = parseBox(o->region[0], o->region[1], "--region");
    const auto frontiers = connection.client().frontiers(query);
    for (const auto& f : frontiers) {
      std::printf("frontier %llu: %llu voxels, centroid %s, distance %.3f m, direction %s\n",
                  static_cast<unsigned long long>(f.id), static_cast<unsigned long long>(f.num_voxels),
                  formatPoint(f.centroid_m).c_str(), f.distance_m, formatPoint(f.direction).c_str());
    }
    std::printf("%zu frontier clusters\n", frontiers.size());
  });
}

void registerInfo(CLI::App& app, Connection& connection) {
  CLI::App* cmd = app.add_subcommand("info", "The map's resolution, frame, bounds, voxel counts and sensor model");
  cmd->callback([&connection] {
    const client::MapInfo info = connection.client().info();
    std::printf("voxel_size_m: %g\nframe_id: %s\n", info.voxel_size_m, info.frame_id.c_str());
    if (info.bounds.isEmpty()) {
      std::printf("bounds: empty\n");
    } else {
      std::printf("bounds: %s .. %s\n", formatPoint(info.bounds.min_m).c_str(), formatPoint(info.bounds.max_m).c_str());
    }
    std::printf("occupied: %llu\nfree: %llu\n", static_cast<unsigned long long>(info.occupied),
                static_cast<unsigned long long>(info.free));
    std::printf("prob_hit: %g\nprob_miss: %g\nclamp: %g %g\noccupied_threshold: %g\nmax_range_m: %g\n"
                "max_distance_m: %g\nmap_version: %llu\n",
                info.prob_hit, info.prob_miss, info.clamp_min, info.clamp_max, info.occupied_threshold, info.max_range_m,
                info.max_distance_m, static_cast<unsigned long long>(info.map_version));
  });
}

}  // namespace

void registerQueryCommands(CLI::App& app, Connection& connection) {
  registerState(app, connection);
  registerBox(app, connection);
  registerSegment(app, connection);
  registerRaycast(app, connection);
  registerDistance(app, connection);
  registerFrontiers(app, connection);
  registerInfo(app, connection);
}

}  // namespace cenote::cli
